"""`python -m afford`: the `afford` command, for tools that run a module (profilers, debuggers)."""

from afford.cli.main import main

if __name__ == "__main__":
    raise SystemExit(main())
