"""Defaults shared by the API and every command, so what ``inspect`` shows is what ``run`` ran."""

DEFAULT_SIZE = (640, 360)  # output size (WxH) when none is given
SCHEDULES = ("declaration", "async-early")  # --schedule choices (rgraph.ir.schedule)
DEFAULT_SCHEDULE = "declaration"
