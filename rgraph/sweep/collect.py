"""Renderings of a sweep, in any order, into its :class:`~rgraph.sweep.runner.SweepResult`.

Every rendering is compared with the reference as soon as both are in, its settings' images
and error maps are written and its pixels dropped (the reference's are kept), so the
one-process sweep, which renders the reference first, holds two images at a time. Rows,
notes and rendering indices follow the settings' order, never the order renderings arrived
in: a parallel sweep's tables equal the one-process sweep's except for measured times.
"""

from __future__ import annotations

from pathlib import Path

from rgraph.sweep import images as image_io
from rgraph.sweep.affected import changed_passes
from rgraph.sweep.compare import METRICS, Images, compare
from rgraph.sweep.runner import Row, SweepRequest, SweepResult, _Rendering, extreme_labels
from rgraph.sweep.settings import Setting, params_key


class Collector:
    """Takes renderings (or failures) by params key as they come; :meth:`result` at the end."""

    def __init__(self, request: SweepRequest, settings: list[Setting], resolved_params: dict[str, dict],
                 out_dir: Path) -> None:
        self.request, self.settings, self.params, self.out_dir = request, settings, resolved_params, out_dir
        self.keys = {s.label: params_key(resolved_params[s.label]) for s in settings}
        self.order: list[tuple] = list(dict.fromkeys(self.keys.values()))  # distinct, in settings order
        self.reference_key = self.keys["reference"]
        self.extremes = set(extreme_labels(settings, request.knobs, request.grid))
        self.renderings: dict[tuple, _Rendering] = {}
        self.failures: dict[tuple, str] = {}
        self.compared: dict[tuple, tuple[dict[str, float | None], list[str]]] = {}
        self.pending: list[tuple] = []
        self.error_maps: dict[str, list[str]] = {}
        self.with_image: set[tuple] = set()  # keys whose rendering gave a display image
        out_dir.mkdir(parents=True, exist_ok=True)

    def add(self, key: tuple, rendering: _Rendering | None, error: str | None = None) -> None:
        """A finished rendering of params ``key`` (or why it failed)."""
        if rendering is None:
            self.failures[key] = error or "failed"
        else:
            self.renderings[key] = rendering
        if key == self.reference_key:
            for waiting in [key, *self.pending]:
                self._finish(waiting)
            self.pending = []
        elif self.reference_key in self.renderings or self.reference_key in self.failures:
            self._finish(key)
        else:
            self.pending.append(key)

    def extreme_slugs(self, key: tuple) -> tuple[str, ...]:
        """Slugs of the settings of params ``key`` whose error maps are kept."""
        return tuple(s.slug for s in self.settings if self.keys[s.label] == key and s.label in self.extremes)

    def reference_images(self) -> Images | None:
        """The reference's images once it rendered (kept to the end), else None."""
        reference = self.renderings.get(self.reference_key)
        return reference.images if reference is not None else None

    def _finish(self, key: tuple) -> None:
        rendering = self.renderings.get(key)
        if rendering is None:
            return
        reference = self.renderings.get(self.reference_key)
        if rendering.compared is not None:  # its worker had the reference
            self.compared[key] = rendering.compared
        elif reference is None:
            self.compared[key] = (dict.fromkeys(METRICS), [])
        else:
            self.compared[key] = compare(reference.images, rendering.images)
        if rendering.images.ldr is not None:
            self.with_image.add(key)
        for s in self.settings:
            if self.keys[s.label] == key:
                self._write_images(s, reference, rendering)
        if key != self.reference_key:
            rendering.images, rendering.png = Images(None, None), None  # compared and written: free the pixels

    def _write_images(self, s: Setting, reference: _Rendering | None, rendering: _Rendering) -> None:
        from rgraph.sweep import plots  # matplotlib: only when sweeping

        test = rendering.images.ldr
        if test is None:
            return
        image_io.save_png(self.out_dir / f"images/{s.slug}.png", rendering.png or test)
        ref = reference.images.ldr if reference is not None else None
        if s.label in self.extremes and ref is not None and ref.shape == test.shape:
            self.error_maps[s.label] = plots.write_error_maps(self.out_dir, s.slug, ref, test,
                                                              rendering.error_maps.get(s.slug))

    def result(self) -> SweepResult:
        """The sweep's result once every distinct setting was added."""
        from rgraph.vk.errors import ExecutionError

        missing = [k for k in self.order if k not in self.renderings and k not in self.failures]
        if missing:
            raise RuntimeError(f"{len(missing)} setting(s) never reported")
        if not self.renderings:
            raise ExecutionError("every setting failed: " + "; ".join(
                f"{s.label}: {self.failures[self.keys[s.label]]}" for s in self.settings))
        notes: list[str] = []
        rows: list[Row] = []
        failures: dict[str, str] = {}
        seen: list[tuple] = []

        def note(text: str) -> None:
            if text not in notes:
                notes.append(text)

        for s in self.settings:
            key = self.keys[s.label]
            if key not in seen:
                seen.append(key)
                if key in self.renderings:
                    for n in self.renderings[key].notes:
                        note(n)
            if key in self.failures:
                failures[s.label] = self.failures[key]
                note(f"{s.label}: not rendered: {self.failures[key]}")
                rows.append(Row(s, self.params[s.label], {}, None, dict.fromkeys(METRICS), [], None, seen.index(key)))
                continue
            rendering = self.renderings[key]
            values, more = self.compared[key]
            for m in more:
                note(f"{s.label}: {m}")
            image = f"images/{s.slug}.png" if key in self.with_image else None
            rows.append(Row(s, self.params[s.label], rendering.pass_ms, rendering.total_ms, values,
                            rendering.messages, image, seen.index(key)))
        if self.reference_key in self.failures:
            note("the reference was not rendered: no error metrics")
        plans = [self.renderings[k].plan for k in self.order if k in self.renderings]
        first = self.renderings.get(self.reference_key) or self.renderings[next(k for k in self.order
                                                                                if k in self.renderings)]
        pass_names: list[str] = []
        for plan in plans:
            pass_names += [p["name"] for p in plan["passes"] if p["name"] not in pass_names]
        position = {p["name"]: i for i, p in enumerate(first.plan["passes"])}
        pass_names.sort(key=lambda n: position.get(n, len(position)))
        outputs = image_io.output_image_resources(first.plan)
        result = SweepResult(
            request=self.request, graph_name=first.plan["graph"], scene=first.plan.get("scene"),
            device=first.device, defaults=self.params["default"], rows=rows, pass_names=pass_names, notes=notes,
            error_maps={s.label: self.error_maps[s.label] for s in self.settings if s.label in self.error_maps},
            output_name=outputs[0]["name"] if outputs else None, reference_params=self.params["reference"],
            failures=failures, plans={k: self.renderings[k].plan for k in self.order if k in self.renderings})
        for knob in self.request.knobs:
            done = [self.renderings[k] for k in dict.fromkeys(params_key(r.params) for r in result.rows_for_knob(knob.name))
                    if k in self.renderings]
            result.knob_passes[knob.name] = changed_passes(knob.name, [r.plan for r in done],
                                                           [r.params_read for r in done])
        return result
