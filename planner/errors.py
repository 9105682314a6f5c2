"""Errors the planner raises for input it cannot plan.

Every error names the input it is about (``input_name``) and says what is wrong in words a
farmer can act on; ``str(error)`` reads ``"<input>: <problem>"``. The web layer maps these
classes to HTTP statuses in one table and the command line prints them as ``error: …``.
"""

from __future__ import annotations


class PlannerError(ValueError):
    """Base class: a request the planner refuses.

    Parameters
    ----------
    input_name : str
        The request field at fault, as named at the edges (``field``, ``interval_m``,
        ``start`` …).
    problem : str
        What is wrong with it, in plain words.
    """

    def __init__(self, input_name: str, problem: str) -> None:
        super().__init__(f"{input_name}: {problem}")
        self.input_name = input_name
        self.problem = problem


class InvalidFieldError(PlannerError):
    """The field boundary is not a polygon that can be planned (shape, size, place)."""


class InvalidParameterError(PlannerError):
    """A planning parameter is out of its valid range (interval, angle, start, finish …)."""


class PlanTooLargeError(PlannerError):
    """The plan would exceed the line limit; refused before any work is done."""


class UnreadableFileError(PlannerError):
    """A file that cannot be read: unknown or binary, malformed, or refused for safety.

    ``input_name`` is the file's name, so the message says which file and what was wrong.
    """


class FieldChoiceError(InvalidFieldError):
    """A file holds several fields and none (or no known one) was chosen.

    Parameters
    ----------
    input_name : str
        The file's name.
    problem : str
        What is wrong, in plain words.
    choices : list of tuple
        ``(index, feature_id, name, area_m2)`` of every field in the file, so a caller can
        list them (the CLI prints them; the page shows them on the map).
    """

    def __init__(
        self,
        input_name: str,
        problem: str,
        choices: list[tuple[int, str | None, str | None, float]],
    ) -> None:
        super().__init__(input_name, problem)
        self.choices = choices
