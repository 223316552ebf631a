// The ES modules' words in the page's language. Every sentence a person reads goes through t("..."), in English;
// the page's <html lang> names the language, and ./i18n/<lang>.js (generated from the gettext catalogue by
// `make translations`) holds the translations. Values go in by name: t("{name} is driving.", { name }).
//
// The catalogue is loaded before any module that imports this one runs (top-level await), so module-level
// constants may call t() too. Numbers, dates and times: number(), dateTime() and time() format per the language (dates
// and times in the reader's variant of it: DATE_LOCALE).

const language = (globalThis.document?.documentElement?.lang || "en").split("-")[0].toLowerCase();

async function load() {
  if (language === "en") return {};
  try {
    return (await import(`./i18n/${language}.js`)).default;
  } catch {
    return {};  // a language without a catalogue reads English, never a broken page
  }
}

const messages = await load();

/** The page's language code, "en" or "es". */
export const LANGUAGE = language;

/** Dates and times in the reader's own variant of the page's language, from the browser's preferred languages: a
 * reader in Britain reads "29 Dec, 15:04", one in the United States "Dec 29, 03:04 PM" (the page's language when
 * the browser prefers no variant of it). */
export const DATE_LOCALE = (globalThis.navigator?.languages ?? [])
  .find((tag) => tag.split("-")[0].toLowerCase() === language) ?? language;

/** text in the page's language, with each {name} replaced by values[name]. */
export function t(text, values = undefined) {
  const translated = messages[text] || text;
  if (!values) return translated;
  return translated.replace(/\{(\w+)\}/g, (whole, name) => (name in values ? String(values[name]) : whole));
}

/** A number as the page's language writes it: 1,234.5 in English, 1234,5 in Spanish. */
export function number(value, options = {}) {
  return new Intl.NumberFormat(language, options).format(value);
}

const PLURALS = new Intl.PluralRules(language);

/** Whether count takes the singular in the page's language ("1 cell", "1 casilla"; "0 cells", "1,5 casillas"): pick
 * between two whole sentences, each its own t("..."), so both reach the catalogue. */
export function isSingular(count) {
  return PLURALS.select(count) === "one";
}

// "." in English, "," in Spanish.
const DECIMAL_SIGN = new Intl.NumberFormat(language).formatToParts(1.5)
  .find((part) => part.type === "decimal")?.value ?? ".";

/** A number with a fixed count of decimals, in the page's language: value.toFixed(digits) with the language's decimal
 * sign ("0,25" in Spanish). toFixed rounds it, as before, so English reads exactly what toFixed wrote (Intl would round
 * 1.005 up where toFixed writes 1.00). */
export function fixed(value, digits = 1) {
  // A small negative that rounds to zero (a robot standing at -0.001 m) reads 0.00, not -0.00.
  const text = Number(value).toFixed(digits).replace(/^-(?=0(\.0*)?$)/, "");
  return DECIMAL_SIGN === "." ? text : text.replace(".", DECIMAL_SIGN);
}

/** A moment (Date, ms or ISO text) as the page's language writes a date and time, in the browser's time zone. */
export function dateTime(moment, options = { weekday: "short", day: "numeric", month: "short", hour: "2-digit",
  minute: "2-digit" }) {
  return new Intl.DateTimeFormat(DATE_LOCALE, options).format(new Date(moment));
}

/** A moment's time of day, "09:30". */
export function time(moment) {
  return new Intl.DateTimeFormat(DATE_LOCALE, { hour: "2-digit", minute: "2-digit", hourCycle: "h23" })
    .format(new Date(moment));
}
