"""Command-line entry points (filled in as the subcommands land)."""


def main() -> int:
    """Entry point of ``bt-nav``."""
    raise SystemExit("bt-nav: not implemented yet")
