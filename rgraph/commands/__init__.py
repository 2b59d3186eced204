"""One module per subcommand. Each exposes ``register(subparsers)`` which adds its parser
and sets ``func`` (``args -> exit code``) as the parser default."""

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
