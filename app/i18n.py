"""Languages: gettext catalogs through Babel, for the page, its script and the API's errors.

The catalogs are ``app/locale/<lang>/LC_MESSAGES/messages.po`` (English is the source
language: its msgids are the English text, so it has no catalog). They are compiled with
Babel's API the first time a language is used, in memory, so no ``.mo`` file is committed or
written next to the code. Three users:

- the templates: ``{{ _('Draw field') }}`` through Jinja2's i18n extension
  (:func:`install_jinja`), in the language of the request (:func:`use_language`);
- the page's script: ``GET /i18n/<lang>.json`` (:func:`catalog_messages`), looked up by
  ``t()`` in ``static/js/i18n.js``;
- the API's error answers: :func:`app.i18n_errors.translate_detail`.

A language is chosen by the ``tillpath_lang`` cookie (set when the person switches) and else
by the request's ``Accept-Language``.
"""

from __future__ import annotations

import gettext as gettext_module
import io
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from functools import cache
from pathlib import Path
from typing import Final

from babel.messages.catalog import Catalog
from babel.messages.mofile import write_mo
from babel.messages.pofile import read_po
from babel.support import Translations
from jinja2 import Environment

#: Where the ``.po`` files live: ``<LOCALE_DIR>/<lang>/LC_MESSAGES/messages.po``.
LOCALE_DIR: Final = Path(__file__).resolve().parent / "locale"
DOMAIN: Final = "messages"
#: The languages offered, by code, with their names in their own language.
LANGUAGES: Final[dict[str, str]] = {"en": "English", "id": "Bahasa Indonesia"}
DEFAULT_LANGUAGE: Final = "en"
#: The cookie that remembers the person's choice (the page sets it; the server reads it).
LANGUAGE_COOKIE: Final = "tillpath_lang"

_current: ContextVar[str] = ContextVar("tillpath_language", default=DEFAULT_LANGUAGE)


def po_path(lang: str) -> Path:
    """Return the path of the ``.po`` catalog of ``lang``."""
    return LOCALE_DIR / lang / "LC_MESSAGES" / f"{DOMAIN}.po"


@cache
def load_catalog(lang: str) -> Catalog | None:
    """Read the ``.po`` catalog of ``lang``; None for the source language or an unknown one."""
    path = po_path(lang)
    if lang == DEFAULT_LANGUAGE or lang not in LANGUAGES or not path.is_file():
        return None
    with path.open("rb") as po:
        return read_po(po, locale=lang, domain=DOMAIN)


@cache
def translations(lang: str) -> gettext_module.NullTranslations:
    """Return the compiled translations of ``lang`` (compiled in memory, once per process).

    Parameters
    ----------
    lang : str
        A code of :data:`LANGUAGES`; anything else gets the English source text.

    Returns
    -------
    gettext.NullTranslations
        ``babel.support.Translations`` for a translated language.
    """
    catalog = load_catalog(lang)
    if catalog is None:
        return gettext_module.NullTranslations()
    compiled = io.BytesIO()
    write_mo(compiled, catalog, use_fuzzy=False)
    compiled.seek(0)
    return Translations(fp=compiled, domain=DOMAIN)


@cache
def catalog_messages(lang: str) -> dict[str, str | list[str]]:
    """Return ``{msgid: translation}`` for the page's script; plural entries map to a list.

    Untranslated and fuzzy entries are left out, so the script falls back to the English text.
    The source language answers an empty mapping.
    """
    catalog = load_catalog(lang)
    messages: dict[str, str | list[str]] = {}
    if catalog is None:
        return messages
    for message in catalog:
        if not message.id or message.fuzzy:
            continue
        if isinstance(message.id, tuple):
            forms = [str(form) for form in message.string or ()]
            if all(forms):
                messages[str(message.id[0])] = forms
        elif message.string:
            messages[str(message.id)] = str(message.string)
    return messages


def parse_accept_language(header: str | None) -> list[str]:
    """Return the language codes of an ``Accept-Language`` header, most wanted first.

    Examples
    --------
    >>> parse_accept_language("id-ID,id;q=0.9,en-US;q=0.8,en;q=0.7")
    ['id-ID', 'id', 'en-US', 'en']
    >>> parse_accept_language("en;q=0.5, id")
    ['id', 'en']
    """
    weighted: list[tuple[float, int, str]] = []
    for position, part in enumerate((header or "").split(",")):
        code, _, params = part.strip().partition(";")
        quality = 1.0
        params = params.strip()
        if params.startswith("q="):
            try:
                quality = float(params[2:])
            except ValueError:
                quality = 0.0
        if code and code != "*" and quality > 0:
            weighted.append((-quality, position, code))
    return [code for _, _, code in sorted(weighted)]


def negotiate_language(accept_language: str | None, cookie: str | None = None) -> str:
    """Choose the language: the remembered choice, else the first offered one the header asks.

    Examples
    --------
    >>> negotiate_language("id-ID,id;q=0.9,en;q=0.8")
    'id'
    >>> negotiate_language("id-ID", cookie="en")
    'en'
    >>> negotiate_language("fr-FR,de")
    'en'
    """
    if cookie in LANGUAGES:
        return str(cookie)
    for code in parse_accept_language(accept_language):
        primary = code.split("-")[0].split("_")[0].lower()
        if primary in LANGUAGES:
            return primary
        # Malay is close enough to Indonesian that a Malaysian reader is better served by it.
        if primary == "ms":
            return "id"
    return DEFAULT_LANGUAGE


def current_language() -> str:
    """Return the language of the request being handled (English outside one)."""
    return _current.get()


@contextmanager
def use_language(lang: str) -> Iterator[None]:
    """Translate with ``lang`` inside the block (templates rendered there use it)."""
    token = _current.set(lang if lang in LANGUAGES else DEFAULT_LANGUAGE)
    try:
        yield
    finally:
        _current.reset(token)


def gettext(message: str, lang: str | None = None) -> str:
    """Translate ``message`` into ``lang`` (default: the current request's language)."""
    return translations(lang or current_language()).gettext(message)


def ngettext(singular: str, plural: str, n: int, lang: str | None = None) -> str:
    """Translate a message with a plural form, chosen by the count ``n``."""
    return translations(lang or current_language()).ngettext(singular, plural, n)


def install_jinja(env: Environment) -> None:
    """Give ``env`` Jinja2's i18n extension, translating into the current language.

    Templates write ``{{ _('Draw field') }}``; ``pybabel extract`` finds these (babel.cfg).
    """
    env.add_extension("jinja2.ext.i18n")
    env.install_gettext_callables(  # type: ignore[attr-defined]
        lambda message: gettext(message),
        lambda singular, plural, n: ngettext(singular, plural, n),
        newstyle=False,
    )
