"""``rgraph sweep``: what accuracy costs in time.

Renders a graph under several settings of its quality params (knobs), times every pass
on the GPU and measures each image's error against a reference setting.

Modules, one job each: :mod:`settings` (knob parsing and expansion), :mod:`metrics`
(PSNR, SSIM, HDR metrics), :mod:`flip` (optional NVIDIA FLIP), :mod:`images` (reading
images out of a run), :mod:`runner` (compile and execute every setting), :mod:`pareto`
(Pareto fronts), :mod:`writers` (CSV, Markdown, PNG) and :mod:`plots` (Pareto plots,
error maps).
"""
