// Translations on the page: a small lookup over the compiled gettext catalog (app/i18n.py).
//
//   import { t, tn } from "./i18n.js";
//   t("Draw field")                                  // "Gambar sawah" in Indonesian
//   t("Saved “{name}”.", { name })                  // named placeholders, never string pieces
//   tn("{count} line", "{count} lines", n, { count: n })
//
// The English text is the key (gettext's msgid); `pybabel extract` finds every t(), _() and tn()
// in static/js (babel.cfg), so a new string is: wrap it, run `make messages`, translate it in
// app/locale/id/LC_MESSAGES/messages.po. Numbers given as placeholders are formatted for the
// language (0,56 in Indonesian); format units with format.js.

const root = document.documentElement;

/** The page's language, as the server chose it (`<html lang>`). */
export const lang = root.lang || "en";

/** Languages the page offers; the server renders the switch from the same table. */
export const LANGUAGE_COOKIE = "tillpath_lang";
const LANGUAGE_KEY = "tillpath.lang";

let messages = {};

async function loadCatalog() {
  const url = root.dataset.catalogUrl;
  if (!url || lang === "en") return;
  try {
    const response = await fetch(url, { headers: { Accept: "application/json" } });
    if (response.ok) messages = (await response.json()).messages ?? {};
  } catch {
    // No network and no cached catalog: the English text shows, the page still works.
  }
}

await loadCatalog();

const numberFormat = new Intl.NumberFormat(lang, { maximumFractionDigits: 6 });

function fill(text, params) {
  return text.replace(/\{([A-Za-z_][A-Za-z0-9_]*)\}/g, (whole, name) => {
    if (!(name in params)) return whole;
    const value = params[name];
    return typeof value === "number" ? numberFormat.format(value) : String(value);
  });
}

/**
 * Translate `message` (its English text) and fill its `{placeholders}` from `params`.
 *
 * @param {string} message The English text, exactly as in the catalog.
 * @param {Object<string, string|number>} [params] Values for the placeholders.
 * @returns {string}
 */
export function t(message, params = {}) {
  const translated = messages[message];
  return fill(typeof translated === "string" ? translated : message, params);
}

/** gettext's name for t(), for those who prefer it. */
export const _ = t;

const pluralRules = new Intl.PluralRules(lang);

/**
 * Translate a message whose words depend on a count `n` ("1 line", "2 lines").
 *
 * @param {string} singular English for one.
 * @param {string} plural English for many.
 * @param {number} n The count.
 * @param {Object<string, string|number>} [params] Values for the placeholders.
 */
export function tn(singular, plural, n, params = {}) {
  const forms = messages[singular];
  let text;
  if (Array.isArray(forms) && forms.length > 0) {
    text = forms.length === 1 ? forms[0] : forms[pluralRules.select(n) === "one" ? 0 : 1] ?? forms[0];
  } else {
    text = n === 1 ? singular : plural;
  }
  return fill(text, params);
}

/** True on a touch screen: the page says "Tap" there, "Click" elsewhere. */
export const touchScreen = window.matchMedia("(pointer: coarse)").matches;

/** Pick the touch or the mouse wording of the same sentence (both are wrapped in t()). */
export function tapOrClick(tapText, clickText) {
  return touchScreen ? tapText : clickText;
}

/** Remember `code` as the person's language and show the page in it. */
export function switchLanguage(code) {
  try {
    localStorage.setItem(LANGUAGE_KEY, code);
  } catch {
    // The cookie below is what the server reads; localStorage only mirrors it.
  }
  document.cookie = `${LANGUAGE_COOKIE}=${encodeURIComponent(code)}; path=/; max-age=31536000; SameSite=Lax`;
  window.location.reload();
}

/**
 * The cookie can be lost (cleared, another port) while localStorage keeps the choice: put it
 * back, so the next page the server renders is in the remembered language.
 */
export function restoreLanguageChoice() {
  let stored = null;
  try {
    stored = localStorage.getItem(LANGUAGE_KEY);
  } catch {
    return;
  }
  const hasCookie = document.cookie.split("; ").some((c) => c.startsWith(`${LANGUAGE_COOKIE}=`));
  if (stored && !hasCookie) {
    document.cookie = `${LANGUAGE_COOKIE}=${encodeURIComponent(stored)}; path=/; max-age=31536000; SameSite=Lax`;
    if (stored !== lang) window.location.reload();
  }
}
