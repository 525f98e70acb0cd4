"""Exceptions raised by raycast.

The compiled library reports a typed error kind; each kind is one class here, so callers
catch what they can act on instead of matching message text.
"""


class RaycastError(Exception):
    """Base class of every error raycast raises about a scene or a request.

    ``code`` is the problem's stable code, the same names ``raycast check`` reports: the
    reader's own where it gives one (a glTF-Validator code such as ``ACCESSOR_TOO_LONG``,
    ``USD_INVALID_PATH``), else ``FAILED``, ``USAGE`` or ``NOT_FOUND`` by the class."""

    code: str = "FAILED"


class SceneError(RaycastError):
    """The scene file could not be read or is not valid (the message names the file)."""


class SceneNotFoundError(SceneError, FileNotFoundError):
    """The scene file does not exist. As a ``FileNotFoundError`` it carries ``errno``
    (``ENOENT``) and ``filename``; its message is raycast's one line naming the file."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else super().__str__()


class UsageError(RaycastError, ValueError):
    """The request cannot be carried out as asked (an invalid option or combination)."""


class RaycastWarning(UserWarning):
    """A warning about a loaded scene (an empty scene, a pose drawn at its default, something
    of the file not applied): the same lines the command line prints as ``warning:``, issued
    once per load with :func:`warnings.warn`. ``Scene.info()["warnings"]`` lists them too."""
