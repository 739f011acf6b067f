"""The CLI's own error, apart from the commands so that every command module can raise it."""

from afford.errors import UserError


class CLIError(UserError):
    """A user mistake: printed as one line, exit status 2."""
