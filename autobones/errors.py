"""The one exception type the library raises for problems a user can act on."""


class AutobonesError(ValueError):
    """Bad input or an impossible request: the message says what and how to fix it.

    A ``ValueError`` (issue #33), so code written ``except ValueError`` around the API keeps working;
    the API raises it, naming the argument, for a wrong type, shape or value as well.

    The CLI prints the message as one line and exits with code 2; any other
    exception is a bug in autobones.
    """


def counted(n, noun, plural=None):
    """``"1 face"``, ``"2 faces"``: a count and its noun, agreeing, for messages (``plural`` when not noun + s)."""
    return f"{n} {noun if n == 1 else (plural or noun + 's')}"
