"""One module per subcommand. Each exposes ``register(subparsers)`` which adds its parser
and sets ``func`` (``args -> exit code``) as the parser default.

``COMMAND_HELP`` is the one-line help of each command (``rgraph --help`` lists it without
importing the command modules; tests/cli checks it against each module's own parser)."""

COMMAND_MODULES = [
    "validate",
    "compile",
    "inspect",
    "check",
    "run",
    "mutate",
    "sweep",
    "place",
    "device_profile",
    "devices",
    "graphs",
    "schema",
    "completion",
]

COMMAND_HELP = {
    "validate": "check a graph file (and scene) for errors",
    "compile": "compile a graph into a plan JSON",
    "inspect": "human views of a plan",
    "check": "replay a plan with an independent happens-before model and report hazards",
    "run": "compile and execute a graph (or a plan JSON) on a Vulkan device",
    "mutate": "mutate every barrier of a compiled graph and report which oracle catches each mutant",
    "sweep": "render quality-knob settings; GPU time per pass and error against a reference",
    "place": "place a lifetime trace (MiniMalloc CSV) under a memory policy",
    "device-profile": "capture a device profile (limits, memory requirements)",
    "devices": "list the Vulkan physical devices (indices for --device/--devices)",
    "graphs": "list the bundled graphs",
    "schema": "print the JSON Schema of graph files",
    "completion": "print a shell completion script",
}
