"""The one base of the errors a user can cause: a bad file, option, dataset or request.

The CLI prints any of them as one line (`afford: error: ...`, exit status 2) and lets every
other exception through as the bug it is. Each is still a ValueError, as it always was.
"""

import sys
from collections.abc import Callable


class UserError(ValueError):
    """A mistake in what the user gave (a file, an option, a dataset); the message names it."""


def exit_on_user_error(main: Callable[[], object]) -> None:
    """Run a script's `main()`; a UserError ends it with one line (`error: ...`, status 2)
    instead of a traceback, as the CLI does. For the scripts in benchmarks/."""
    try:
        main()
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(2) from None
