"""The add-on's one exception: a failure to show the user as one line."""


class SSSError(Exception):
    """A failure to show the user as one line."""
