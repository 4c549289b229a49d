"""The one exception type the library raises for problems a user can act on."""


class AutobonesError(Exception):
    """Bad input or an impossible request: the message says what and how to fix it.

    The CLI prints the message as one line and exits with code 2; any other
    exception is a bug in autobones.
    """
