"""rgraph: a declarative render-graph compiler for Vulkan."""

__version__ = "0.1.0"
