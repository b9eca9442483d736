"""``python -m bt_nav.cli <command>``: what the launchers start, with the caller's interpreter."""

from bt_nav.cli import main

raise SystemExit(main())
