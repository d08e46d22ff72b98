"""Exceptions raised for bad input; the command line prints them as one line and exits with status 2."""

from __future__ import annotations


class GluError(ValueError):
    """Base class of every error caused by bad input (a file, a node name, a value, evidence)."""


class DataError(GluError):
    """A data file is missing, unreadable or does not follow the expected format."""


class ModelError(GluError):
    """A model file is malformed or a model does not have the expected structure."""


class UnknownNodeError(GluError):
    """A node name that the model does not have."""


class UnknownValueError(GluError):
    """A value that the node does not take."""


class EvidenceError(GluError):
    """Evidence that is malformed: a node given twice, soft evidence that is not a distribution, …"""


class ImpossibleEvidenceError(EvidenceError):
    """Evidence of probability zero under the model."""


class FetchError(GluError):
    """A download failed or its checksum did not match."""


class GrammarError(GluError):
    """A grammar (HTK HParse syntax) that is malformed, refers to an undefined or recursive ``$variable``, …

    Attributes
    ----------
    source : the file name, or ``"<string>"``
    line, column : 1-based position of the problem, or None when it has no single place
    reason : the message without the position
    """

    def __init__(
        self, reason: str, source: str = "<string>", line: int | None = None, column: int | None = None
    ):
        self.reason, self.source, self.line, self.column = reason, source, line, column
        where = source if line is None else f"{source}:{line}:{column}"
        super().__init__(f"{where}: {reason}")


class VocabularyError(GluError):
    """A sentence or grammar uses words the model has no probability for."""


class OutputError(GluError):
    """No output folder was given where one is needed (an installed glu has no project folders)."""


class MissingDependencyError(GluError):
    """An optional dependency (an extra such as ``glu[notebooks]``) that a command needs is not installed."""


class ParameterError(GluError):
    """A notebook parameter that the notebook does not declare, of the wrong type or out of range."""


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM; handled as an interrupt (the command line exits with status 143)."""
