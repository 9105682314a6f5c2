"""Languages: the catalogs are complete, every string shown is in them, the API answers in them.

The extraction test runs Babel's own extractor over templates/, static/js and app/ exactly as
``make messages`` does (babel.cfg), so a string wrapped in ``_()``/``t()`` but never added to
the catalog fails here, and so does one added but never translated.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from babel.messages.extract import extract_from_dir
from babel.messages.frontend import parse_mapping_cfg
from fastapi.testclient import TestClient

from app import errors, i18n
from app.i18n_errors import ERROR_MESSAGES, translate_detail

ROOT = Path(__file__).resolve().parents[2]
#: The keywords of `make messages`: _() and t() in templates and script, tn() for plurals,
#: N_() for the API's error templates.
KEYWORDS = {"_": None, "t": None, "tn": (1, 2), "N_": None, "gettext": None, "ngettext": (1, 2)}
TRANSLATED = [lang for lang in i18n.LANGUAGES if lang != i18n.DEFAULT_LANGUAGE]
PLACEHOLDER = re.compile(r"\{([A-Za-z_]\w*)\}")


def extracted_messages() -> dict[str, str]:
    """Every msgid that ``pybabel extract -F babel.cfg`` finds, with where it was found."""
    with (ROOT / "babel.cfg").open() as cfg:
        method_map, options_map = parse_mapping_cfg(cfg)
    found: dict[str, str] = {}
    for filename, _lineno, message, _comments, _context in extract_from_dir(
        str(ROOT), method_map, options_map, keywords=KEYWORDS
    ):
        msgid = message[0] if isinstance(message, tuple) else message
        if msgid:
            found.setdefault(msgid, filename)
    return found


def test_extraction_finds_the_page_the_script_and_the_api_errors() -> None:
    found = extracted_messages()
    assert found["Generate path"].startswith("templates")
    assert found["Planning the path…"].startswith("static")
    assert found["must be between {low} and {high} m, got {value}"].startswith("app")
    assert len(found) > 200


@pytest.mark.parametrize("lang", TRANSLATED)
def test_every_extracted_string_is_in_the_catalog(lang: str) -> None:
    catalog = i18n.load_catalog(lang)
    assert catalog is not None
    ids = {m.id[0] if isinstance(m.id, tuple) else m.id for m in catalog if m.id}
    missing = {msgid: where for msgid, where in extracted_messages().items() if msgid not in ids}
    assert missing == {}, f"run `make messages` and translate these in {i18n.po_path(lang)}"


@pytest.mark.parametrize("lang", TRANSLATED)
def test_every_catalog_string_is_translated_with_the_same_placeholders(lang: str) -> None:
    catalog = i18n.load_catalog(lang)
    assert catalog is not None
    problems = []
    for message in catalog:
        if not message.id:
            continue
        ids = message.id if isinstance(message.id, tuple) else (message.id,)
        strings = message.string if isinstance(message.string, tuple) else (message.string,)
        if message.fuzzy or not all(strings):
            problems.append(f"untranslated: {ids[0]!r}")
            continue
        wanted = set(PLACEHOLDER.findall(ids[0]))
        for text in strings:
            if set(PLACEHOLDER.findall(str(text))) != wanted:
                problems.append(f"placeholders differ: {ids[0]!r} -> {text!r}")
    assert problems == []


def test_catalog_route_serves_the_compiled_catalog(client: TestClient) -> None:
    answer = client.get("/i18n/id.json")
    assert answer.status_code == 200
    body = answer.json()
    assert body["lang"] == "id"
    assert body["messages"]["Generate path"] == i18n.gettext("Generate path", "id") != ""
    assert body["messages"]["{count} line"] == [i18n.ngettext("{count} line", "x", 2, "id")]
    assert client.get("/i18n/en.json").json() == {"lang": "en", "messages": {}}
    assert client.get("/i18n/fr.json").json()["lang"] == "en"


@pytest.mark.parametrize(
    ("headers", "cookie", "lang", "draw"),
    [
        ({"Accept-Language": "id-ID,id;q=0.9,en;q=0.8"}, None, "id", "Gambar sawah"),
        ({"Accept-Language": "en-GB,en;q=0.9"}, None, "en", "Draw field"),
        ({"Accept-Language": "id-ID"}, "en", "en", "Draw field"),
        ({"Accept-Language": "en"}, "id", "id", "Gambar sawah"),
    ],
)
def test_page_language_follows_the_browser_then_the_remembered_choice(
    client: TestClient, headers: dict[str, str], cookie: str | None, lang: str, draw: str
) -> None:
    if cookie:
        client.cookies.set(i18n.LANGUAGE_COOKIE, cookie)
    page = client.get("/", headers=headers)
    assert page.status_code == 200
    assert f'<html lang="{lang}"' in page.text
    assert f'id="draw-field">{draw}</button>' in page.text
    assert "Accept-Language" in page.headers["vary"]
    client.cookies.clear()


def test_api_errors_are_in_indonesian_when_asked(
    client: TestClient, paper_body: dict[str, Any]
) -> None:
    body = {**paper_body, "interval_m": 0}
    english = client.post("/api/plans/preview", json=body)
    indonesian = client.post(
        "/api/plans/preview", json=body, headers={"Accept-Language": "id-ID,id;q=0.9"}
    )
    assert english.status_code == indonesian.status_code == 422
    assert english.json()["detail"].startswith("interval_m: must be between 0.2 and 50 m")
    # The input keeps its JSON name (clients point at it); the problem is Indonesian, with
    # Indonesian numbers.
    assert indonesian.json()["detail"] == "interval_m: harus antara 0,2 dan 50 m, bukan 0"
    missing = client.get("/api/plans/999999", headers={"Accept-Language": "id"})
    assert missing.status_code == 404
    assert missing.json()["detail"] == "rencana 999999 tidak ditemukan"
    invalid = client.post("/api/plans/preview", json={}, headers={"Accept-Language": "id"})
    assert "wajib diisi" in invalid.json()["detail"]


def test_every_validation_wording_has_a_translatable_template() -> None:
    # Every fixed sentence app/errors.py words a validation error with is in the table.
    for problem in errors._TYPE_MESSAGES.values():
        assert translate_detail(f"x: {problem}", "id") != f"x: {problem}", problem


@pytest.mark.parametrize(
    ("detail", "expected"),
    [
        (
            "headland_passes: must be from 0 to 5, got 9",
            "headland_passes: harus 0 sampai 5, bukan 9",
        ),
        (
            "objective: must be 'a' or 'b'; interval_m: is required",
            "objective: harus 'a' or 'b'; interval_m: wajib diisi",
        ),
        ("field: area is 2,345 ha; tillpath plans fields up to 2,000 ha at once", None),
        (
            "field: spans 1,396 km corner to corner; tillpath plans fields up to 25 km across "
            "(is a coordinate mistyped?)",
            "field: membentang 1.396 km dari sudut ke sudut; tillpath merencanakan sawah paling "
            "panjang 25 km (apakah ada koordinat yang salah ketik?)",
        ),
        ("something nobody listed", "something nobody listed"),
        # A list body's item (a batch of fixes) and the answers of a server under load.
        ("[0].t: must lie between 1980 and 2100", "[0].t: harus di antara tahun 1980 dan 2100"),
        (
            "simulation: the server is busy with other work; try again in 2 s",
            "simulation: server sedang sibuk dengan pekerjaan lain; coba lagi dalam 2 detik",
        ),
    ],
)
def test_translate_detail(detail: str, expected: str | None) -> None:
    translated = translate_detail(detail, "id")
    if expected is None:
        assert translated.startswith("field: luasnya 2.345 ha")
    else:
        assert translated == expected
    assert translate_detail(detail, "en") == detail


def test_error_templates_are_whole_sentences_with_named_placeholders() -> None:
    for template in ERROR_MESSAGES:
        assert "{}" not in template and "%" not in template, template


@pytest.mark.parametrize(
    ("detail", "expected"),
    [
        (
            "role: the organisation would have no owner left; make another first",
            "role: organisasi ini tidak akan punya pemilik lagi; jadikan anggota lain pemilik dulu",
        ),
        (
            "username: no user called 'sari'; give a password to make one",
            "username: tidak ada pengguna bernama 'sari'; berikan kata sandi untuk membuatnya",
        ),
        (
            "organisation: a device token belongs to one organisation",
            "organisation: token perangkat hanya milik satu organisasi",
        ),
    ],
)
def test_a_cooperatives_member_errors_are_in_indonesian(detail: str, expected: str) -> None:
    assert translate_detail(detail, "id") == expected
