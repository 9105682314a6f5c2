"""The API's error messages in the request's language (``Accept-Language: id``).

Errors are raised in English everywhere (``planner/`` knows nothing of languages, and the CLI
prints English), as ``"<input>: <problem>"``. Each problem the API can answer is listed below
once, as a whole sentence with named placeholders, marked with ``N_`` so that
``pybabel extract`` puts it in the catalog. :func:`translate_detail` recognises a detail by
these same templates, translates the template and puts the values back, formatted for the
language (``0.2`` is ``0,2`` in Indonesian). A problem not listed stays in English.
"""

from __future__ import annotations

import re
from decimal import Decimal, InvalidOperation
from functools import lru_cache
from typing import Final

from babel.numbers import format_decimal

from app.i18n import DEFAULT_LANGUAGE, gettext


def N_(message: str) -> str:  # noqa: N802 (gettext's name for "mark, do not translate yet")
    """Mark ``message`` for extraction; return it unchanged."""
    return message


#: Every problem the API words, as English templates (placeholders in braces).
ERROR_MESSAGES: Final[tuple[str, ...]] = (
    # app/errors.py: request validation
    N_("is required"),
    N_("is not a known input"),
    N_("must be a number"),
    N_("must be a finite number"),
    N_("must be a whole number"),
    N_("must be true or false"),
    N_("must be a string"),
    N_("must be a JSON object"),
    N_("must be a [lon, lat] pair of numbers"),
    N_("must be a list"),
    N_("must be null"),
    N_("is too long (at most {limit} characters)"),
    N_("is too long"),
    N_("is too short"),
    N_("must be at least {low}"),
    N_("must be greater than {low}"),
    N_("must be at most {high}"),
    N_("must be less than {high}"),
    N_("is not valid JSON text"),
    N_("is not valid"),
    N_("the request is larger than the limit of {limit} bytes"),
    N_("the upload is larger than the limit of {limit} bytes"),
    # app/errors.py, app/db.py: a server under load, values a database cannot store
    N_("the server is busy with other work; try again in {s} s"),
    N_("busy with other writes; nothing was stored, try again in {s} s"),
    N_("every connection is in use; try again in {s} s"),
    N_("not reachable or busy; try again in {s} s"),
    N_("the request conflicts with a change made at the same time; retry"),
    N_(
        "the request conflicts with a change made at the same time; read the object again and retry"
    ),
    N_("holds a value the database cannot store (out of range or a NUL character)"),
    N_("must not contain control characters such as NUL"),
    # planner/validation.py: the field
    N_("must be a Polygon, not {kind}"),
    N_("polygon is empty"),
    N_("boundary has {count} vertices; simplify it to at most {limit}"),
    N_("a coordinate is not a finite number"),
    N_("polygon needs at least 3 distinct vertices"),
    N_("polygon has no area: its vertices lie on one line"),
    N_("polygon is self-intersecting near {where}"),
    N_("polygon is self-intersecting"),
    N_("area is {area} m², too small to plan (it must be more than 1 m²)"),
    N_("area is {area} ha; tillpath plans fields up to 2,000 ha at once"),
    N_(
        "spans {span} km corner to corner; tillpath plans fields up to {limit} km across "
        "(is a coordinate mistyped?)"
    ),
    N_("latitude is outside the 80°S to 84°N range that tillpath plans in"),
    # planner/validation.py: the parameters
    N_("must be between {low} and {high} m, got {value}"),
    N_("must be between {low} and {high} m/s, got {value}"),
    N_("must be at least 0 and less than 180 degrees, got {value}"),
    N_("must be one of {choices}, got {value}"),
    N_("must be a whole number from 0 to 5, got {value}"),
    N_("must be from 0 to 5, got {value}"),
    N_("must be a [lon, lat] pair"),
    N_("must be a number, got {value}"),
    N_("must be a finite number, got {value}"),
    N_("{point} is {distance} km from the field; it must be within 5 km"),
    N_(
        "at {interval} m the field needs at least {count} tillage lines; tillpath plans at "
        "most {limit}: choose a wider interval or a smaller field"
    ),
    # app/tracks.py and its readers (app/track_*.py): uploaded tracks
    N_(
        "is not a track file tillpath can read: expected GPX, CSV with a time,lat,lon "
        "header, or an NMEA 0183 log"
    ),
    N_("has no usable fix ({why})"),
    N_("the CSV file is empty"),
    N_("must lie between 1980 and 2100"),
    N_("is {length} characters long; a time has at most {limit}"),
    N_("heading_deg must be between -360 and 360, got {value}"),
    N_("speed_mps must be between 0 and 100, got {value}"),
    N_("GPX with a DTD, entity declarations or external references is refused"),
    N_("is not a valid GPX file (its root element is <{name}>)"),
    N_("is not well-formed XML ({why})"),
    N_("a <trkpt> needs lat and lon"),
    N_("{value} is not an ISO 8601 time"),
    # accounts (app/accounts.py, app/auth.py, app/errors.py)
    N_("username or password is wrong"),
    N_("too many failed sign-ins for this account; try again in about {minutes} minutes"),
    N_("too many failed sign-ins for this address; try again in about {minutes} minutes"),
    N_("sign in first, or send an API token as `Authorization: Bearer …`"),
    N_("must be {low} to {high} characters long"),
    N_("{name} was just taken; choose another"),
    N_("no user called {name}; give a password to make one"),
    N_("the organisation would have no owner left; make another first"),
    N_("a device token belongs to one organisation"),
    # stored objects
    N_("field {id} not found"),
    N_("token {id} not found"),
    N_("organisation {id} not found"),
    N_("plan {id} not found"),
    N_("simulation {id} not found"),
    N_("run {id} not found"),
    N_("internal error"),
    # last: the catch-all of a choice ("must be 'shortest_path' or 'fewest_lines'")
    N_("must be {expected}"),
)

#: ``"<input>: "`` at the start of a detail: a JSON name, dotted or indexed (``start[0]``).
#: A list body's errors start with the item's index (``[0].t``).
_INPUT = re.compile(
    r"^(?P<input>(?:[a-z_][a-z0-9_]*|\[\d+\])(?:\.[a-z0-9_]+|\[\d+\])*): (?P<rest>.+)$", re.S
)
_PLACEHOLDER = re.compile(r"\{([a-z_]+)\}")
#: A placeholder's value: any text that does not run on into the next "; <input>: " sentence.
_VALUE = r"(?:(?!; [a-z_\[][a-z0-9_.\[\]]*: ).)+?"
_NUMBER = re.compile(r"^-?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?$")


@lru_cache(maxsize=1)
def _patterns() -> tuple[tuple[re.Pattern[str], str], ...]:
    compiled = []
    for template in ERROR_MESSAGES:
        parts = _PLACEHOLDER.split(template)
        regex = "".join(
            re.escape(part) if i % 2 == 0 else f"(?P<{part}>{_VALUE})"
            for i, part in enumerate(parts)
        )
        compiled.append((re.compile(f"^{regex}$", re.S), template))
    return tuple(compiled)


def _format_value(text: str, lang: str) -> str:
    """Write an English number (``2,000``, ``0.2``) in ``lang``'s form; other text as is.

    Plain whole numbers (ids, counts written without separators) are left as they are.
    """
    if not _NUMBER.match(text) or text.lstrip("-").isdigit():
        return text
    try:
        value = Decimal(text.replace(",", ""))
    except InvalidOperation:  # pragma: no cover - the pattern admits only numbers
        return text
    return format_decimal(value, locale=lang, decimal_quantization=False, group_separator=True)


def translate_problem(problem: str, lang: str) -> str:
    """Translate one English problem (without its input name) into ``lang``, if it is listed.

    Examples
    --------
    >>> translate_problem("must be between 0.2 and 50 m, got 0", "en")
    'must be between 0.2 and 50 m, got 0'
    """
    if lang == DEFAULT_LANGUAGE:
        return problem
    return _translated(problem, lang) or problem


def _translated(problem: str, lang: str) -> str | None:
    for pattern, template in _patterns():
        match = pattern.match(problem)
        if match:
            values = {k: _format_value(v, lang) for k, v in match.groupdict().items()}
            try:
                return gettext(template, lang).format(**values)
            except (KeyError, IndexError, ValueError):
                return None  # a translation with a broken placeholder: keep the English
    return None


def _translate_sentence(sentence: str, lang: str) -> str | None:
    match = _INPUT.match(sentence)
    if match:
        problem = _translated(match["rest"], lang)
        return None if problem is None else f"{match['input']}: {problem}"
    return _translated(sentence, lang)


def translate_detail(detail: str, lang: str) -> str:
    """Translate an error ``detail`` (``"<input>: <problem>"``, maybe several joined by ``; ``).

    The input names stay as the JSON names them (``interval_m``), so a client can still tell
    which input is at fault; only the problems are translated.
    """
    if lang == DEFAULT_LANGUAGE:
        return detail
    whole = _translate_sentence(detail, lang)  # some problems contain "; " themselves
    if whole is not None:
        return whole
    return "; ".join(
        _translate_sentence(sentence, lang) or sentence for sentence in detail.split("; ")
    )
