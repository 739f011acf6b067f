"""The one base of the errors a user can cause: a bad file, option, dataset or request.

The CLI prints any of them as one line (`afford: error: ...`, exit status 2) and lets every
other exception through as the bug it is. Each is still a ValueError, as it always was.
"""


class UserError(ValueError):
    """A mistake in what the user gave (a file, an option, a dataset); the message names it."""
