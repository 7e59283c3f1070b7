"""Sub-commands of ``fivid``: one module each, with ``register(subparsers)``."""
