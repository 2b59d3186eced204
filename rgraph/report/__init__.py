"""Human views of a plan dict (docs/plan.md), for ``rgraph inspect``.

Every view reads only the plan JSON, never compiler objects: ``summary`` (header, schedule,
culled passes, stats), ``barriers``, ``memory``, ``dot`` (pass graph, with ``deps``),
``timeline`` (PNG) and ``html``; ``text`` prints the terminal views, ``plan_file`` loads
and checks a plan file.
"""
