"""One module per ``rx90`` subcommand, each with ``register(subparsers)`` and ``run(args)``."""
from . import convert, demo, excite, export_cmd, gains, identify_cmd, model, monitor, payload_cmd, predict, simulate

#: In the order ``rx90 --help`` lists them.
COMMANDS = (model, excite, simulate, convert, identify_cmd, predict, monitor, payload_cmd, gains, export_cmd, demo)
