"""Finds words a person reads that do not go through the catalogue: text of a template outside {{ _("...") }},
and string literals of an ES module outside t("...") that read as English prose. Used by the catalogue test
(tests/unit/test_i18n_catalogue.py) and by `python -m middleware.translations.coverage` (lists them).

What counts as prose, for an ES module's literal: it has a word of two letters or more and is not code — not a
path, selector, CSS class list, event or element name, identifier, key name, shader, SVG path or format. What is
not read by a person is left alone by the context it is written in: `class:`, `querySelector(`, `throw new
Error(` (a message for developers), `.close(` (a WebSocket's close reason, for the server's log), comparisons,
imports, console calls, an object's keys and the ids of aria-describedby/labelledby."""

from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TEMPLATES = ROOT / "client_ui" / "templates"
MODULE_FOLDERS = tuple(ROOT / "client_ui" / "static" / name for name in ("pages", "lib", "panels"))

# Words that are the same in every language the lab speaks: names and acronyms.
NEUTRAL = {"Telelab", "API", "LMS", "LTI", "CSV", "JSON", "MCAP", "OK", "UTC", "WebSocket", "WebGL", "IoU", "RMS",
           "JWKS", "URL", "Moodle", "Canvas", "Pyodide", "Python", "Blockly", "OpenAPI", "AsyncAPI", "ms", "fps",
           "Hz", "MB", "KiB", "kB", "px", "min", "Robot"}

# ---------------------------------------------------------------------------------------------------- templates

_TAG = r"<(?:[^<>{]|\{\{.*?\}\}|\{%.*?%\}|\{(?![{%]))*>"
_EXPRESSION = r"""\{\{(?:[^'"}]|'(?:\\.|[^'\\])*'|"(?:\\.|[^"\\])*"|\}(?!\}))*\}\}"""
_TEMPLATE_TOKEN = re.compile("(" + _EXPRESSION + r"|\{%.*?%\}|\{#.*?#\}|<!--.*?-->|<script\b.*?</script>|"
                             r"<style\b.*?</style>|" + _TAG + ")", re.S)
_READ_ATTRIBUTES = re.compile(r'\b(placeholder|title|aria-label|alt|aria-description|data-label)=(["\'])(.*?)\2', re.S)
_SUBMIT_VALUE = re.compile(r'\bvalue=(["\'])(.*?)\1', re.S)
_WORD = re.compile(r"[A-Za-zÀ-ÿ]{2,}")
_JINJA_LITERAL = re.compile(r"""(?<![\w.])(['"])((?:\\.|(?!\1).)*)\1""")


def _reads_as_words(text: str) -> bool:
    words = _WORD.findall(text)
    return any(word not in NEUTRAL for word in words)


def _without_jinja(text: str) -> str:
    return re.sub(r"\{\{.*?\}\}|\{%.*?%\}|\{#.*?#\}", " ", text, flags=re.S)


_BOOLEAN_ATTRIBUTES = re.compile(r"\s*(selected|checked|disabled|open|hidden|required|multiple|readonly)\s*")


def _expression_prose(expression: str) -> list[str]:
    """English string literals inside a {{ }} expression outside _(...)'s message: 'not waiting', 'students have'
    (a value given to _() is read too: _("%(n)s %(who)s", who='students have') is half English)."""
    found = []
    for match in _JINJA_LITERAL.finditer(expression):
        literal = match.group(2)
        before = expression[:match.start()]
        if re.search(r"\b_\(\s*$|\bgettext\(\s*$|url_for\([^)]*$|format\(\s*$", before):
            continue
        unquoted = _JINJA_LITERAL.sub("", before)
        shown = (unquoted.count("(") == unquoted.count(")") and unquoted.count("[") == unquoted.count("]")
                 and unquoted.count("{") == unquoted.count("}") and re.search(r"(^|\belse|\bor|~)\s*$", before))
        if re.fullmatch(r"[A-Za-z]{2,}", literal):
            if (shown or re.match(r"[A-Z][a-z]", literal)) and literal not in NEUTRAL | {"true", "false"}:
                found.append(literal)  # a word the expression shows: {{ 'done' if finished else ... }}
            continue
        if "%" in literal or not re.search(r"[a-z]{3,}", literal):
            continue  # a format ('%g', '%.0f MB'), a symbol or a code
        if re.fullmatch(r"[\w./:-]*", literal):
            continue
        if literal.startswith("WEBVTT") or literal in ("true", "false") or _BOOLEAN_ATTRIBUTES.fullmatch(literal):
            continue  # a name, an endpoint, a class, a CSS value, an HTML boolean attribute
        if re.search(r"""\w=["']""", literal):
            continue  # HTML attributes given to a macro
        if _reads_as_words(literal):
            found.append(literal)
    return found


def template_strings(text: str) -> list[tuple[int, str]]:
    """(line, text) of each visible string of a template's source outside the catalogue."""
    found: list[tuple[int, str]] = []
    position = 0
    for index, part in enumerate(_TEMPLATE_TOKEN.split(text)):
        line = text.count("\n", 0, position) + 1
        position += len(part)
        if index % 2 == 0:
            if _reads_as_words(part) and not re.fullmatch(r"\s*[\w.:-]*/[\w/.:-]*\s*", part):  # not a path
                found.append((line, " ".join(part.split())))
            continue
        if part.startswith("{{"):
            found += [(line, literal) for literal in _expression_prose(part[2:-2])]
        elif part.startswith("<") and not part.startswith(("<script", "<style", "<!--")):
            values = [m.group(3) for m in _READ_ATTRIBUTES.finditer(part)]
            if re.match(r"<input\b", part) and re.search(r'type="(submit|button|reset)"', part):
                values += [m.group(2) for m in _SUBMIT_VALUE.finditer(part)]
            found += [(line, value) for value in values if _reads_as_words(_without_jinja(value))]
            for value in values:  # only what a person reads: not data-*, class, selected, ...
                for expression in re.findall(_EXPRESSION, value, re.S):
                    found += [(line, literal) for literal in _expression_prose(expression[2:-2])]
    return found


# ---------------------------------------------------------------------------------------------------- ES modules

_REGEX_BEFORE = set("(,=:[!&|?{};+-*%<>~^")
_KEYWORDS_BEFORE_REGEX = ("return", "typeof", "case", "of", "in", "void", "yield", "await", "else")


def _regex_may_start(source: str, index: int) -> bool:
    before = source[:index].rstrip()
    word = re.search(r"(\w+)$", before)
    return not before or before[-1] in _REGEX_BEFORE or bool(word and word.group(1) in _KEYWORDS_BEFORE_REGEX)


def _scan(source: str, index: int, found: list[tuple[str, int, int, list[tuple[int, int]]]], nested: bool) -> int:
    """Reads code from index, adding its literals to found; in a template's ${ } (nested), stops after its }."""
    depth = 0
    while index < len(source):
        char = source[index]
        if source.startswith("//", index):
            end = source.find("\n", index)
            index = len(source) if end < 0 else end
        elif source.startswith("/*", index):
            end = source.find("*/", index + 2)
            index = len(source) if end < 0 else end + 2
        elif char in "\"'":
            end = index + 1
            while end < len(source) and source[end] not in (char, "\n"):
                end += 2 if source[end] == "\\" else 1
            found.append(("str", index, end + 1, []))
            index = end + 1
        elif char == "`":
            index = _scan_template(source, index, found)
        elif char == "/" and _regex_may_start(source, index):
            index += 1
            in_class = False
            while index < len(source) and (source[index] != "/" or in_class) and source[index] != "\n":
                if source[index] == "\\":
                    index += 1
                elif source[index] == "[":
                    in_class = True
                elif source[index] == "]":
                    in_class = False
                index += 1
            index += 1
        elif char == "{":
            depth += 1
            index += 1
        elif char == "}":
            index += 1
            if depth == 0 and nested:
                return index
            depth -= 1
        else:
            index += 1
    return index


def _scan_template(source: str, start: int, found: list[tuple[str, int, int, list[tuple[int, int]]]]) -> int:
    """Adds the template literal at start (and the literals of its ${ } parts) to found; returns its end."""
    holes: list[tuple[int, int]] = []
    entry = ("tpl", start, start, holes)
    found.append(entry)
    index = start + 1
    while index < len(source) and source[index] != "`":
        if source[index] == "\\":
            index += 2
        elif source.startswith("${", index):
            end = _scan(source, index + 2, found, nested=True)
            holes.append((index, end))
            index = end
        else:
            index += 1
    found[found.index(entry)] = ("tpl", start, index + 1, holes)
    return index + 1


def literals(source: str) -> list[tuple[str, int, int, list[tuple[int, int]]]]:
    """(kind, start, end, holes) of the string ('str') and template ('tpl') literals of an ES module, those inside a
    template's ${ } included; holes are the spans of a template's ${ } parts. Comments and regexes are skipped."""
    found: list[tuple[str, int, int, list[tuple[int, int]]]] = []
    _scan(source, 0, found, nested=False)
    return found


_TAGS = {"input", "select", "textarea", "button", "a", "div", "span", "p", "li", "ul", "fieldset", "label", "option",
         "summary", "details", "section", "canvas", "svg", "img", "video", "table", "tr", "td", "th"}
_KEYS = {"Enter", "Escape", "ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight", "Tab", "Space", "Home", "End",
         "PageUp", "PageDown", "Content-Type", "X-CSRFToken", "GET", "POST", "PUT", "DELETE", "PATCH", "Backspace",
         "Shift", "Control", "Alt", "Meta", "NaN", "Infinity", "AbortError", "TimeoutError"}
_CODE_CONTEXT = re.compile(
    r"""(\bclass\s*:\s*|className\s*[+]?=\s*|classList\.\w+\([^)]*|new \w*Error\(\s*|throw\s+|"""
    r"""querySelector(All)?\(\s*|closest\(\s*|matches\(\s*|[!=]==?\s*|\bcase\s+|\bt\(\s*|\b(from|import)\s+|import\(\s*|console\.\w+\([^)]*|"""
    r"""getElementById\(\s*|"aria-(?:describedby|labelledby|controls|owns)"\s*:\s*|\.close\(\s*|reason\s*=\s*|"""
    r"""dataset\.\w+\s*===?\s*|\.key\s*===?\s*)$""")


HOLE = "§"  # a template literal's ${ } part, in the text checked


def reads_as_prose(text: str) -> bool:
    """Is a literal's text (its ${ } parts as HOLE) something a person reads?"""
    if not re.search(r"[A-Za-z]{2,}", text) or text in _KEYS:
        return False
    if not re.search(r"\s", text) and re.search(r"[/=&]|:$", text):
        return False  # a path, a query, a scheme
    if re.search(r"\w\[", text) or re.match(r"\s*[.#\[:>@/]", text):
        return False  # a selector
    if re.search(r"[§\d]px\b|\bvoid main|gl_|^\w+\(|--|__|=>|https?:|/api/|/ws/", text):
        return False  # CSS, a shader, a call, BEM classes, a URL
    if {word.strip() for word in text.split(",")} <= _TAGS:
        return False
    if not re.search(r"\s", text) and HOLE in text and not re.search(r"[A-Za-z]{3,}", text):
        return False  # an SVG path or a built number
    if re.fullmatch(r"[\w$-]+", text) and not re.match(r"[A-Z][a-z]", text):
        return False  # identifiers, kebab-case keys, lowercase single words (event and state names)
    if HOLE in text and re.fullmatch(r"[\w$§-]+", text):
        return False  # a built id: panel-title-${id}
    if re.fullmatch(r"[A-Z][A-Za-z0-9]*[A-Z][A-Za-z0-9]*", text) or re.fullmatch(r"[A-Z0-9_\s\\n§]+", text):
        return False  # CamelCase identifiers, CONSTANTS, WEBVTT
    if re.fullmatch(r"[a-z][\w-]*(\s+[a-z][\w-]*)*", text) and re.search(r"[-_]", text):
        return False  # class lists
    if re.match(r"(image|text|application|video|audio)/", text):
        return False
    if re.search(r"=[^ ]*;|;\s*\w+=|\.js$|\bimport \w+", text):
        return False  # a cookie, a file name, code
    if re.fullmatch(r"\s*[a-z_]+ §\s*|[^a-z]*[{}][^a-z]*(\s[a-z]+\s*[{}]?)?\s*", text):
        return False  # a keyword of the plan language with its value: "say §", "§} else {"
    return _reads_as_words(text)


def module_strings(source: str) -> list[tuple[int, str]]:
    """(line, text) of each literal of an ES module that reads as prose and does not go through t()."""
    found = []
    in_call_until = -1  # the end of the last literal given to t(): "..." + "..." goes on with it
    for _kind, start, end, holes in literals(source):
        before = source[max(0, start - 60):start]
        if re.search(r"\bt\(\s*$", before) or (in_call_until >= 0 and re.fullmatch(r"\s*\+\s*",
                                                                            source[in_call_until:start])):
            in_call_until = end
            continue
        in_call_until = -1
        line_end = source.find("\n", end)
        if "i18n: not prose" in source[end:line_end if line_end >= 0 else len(source)]:
            continue  # a line that says so: plan language, a default value written in code
        if _CODE_CONTEXT.search(before):
            continue
        if re.match(r"\s*:", source[end:end + 3]) and re.search(r"[{,]\s*$", before):
            continue  # an object's key
        text, position = "", start + 1
        for hole_start, hole_end in holes:
            text += source[position:hole_start] + HOLE
            position = hole_end
        text += source[position:end - 1]
        if reads_as_prose(text):
            found.append((source.count("\n", 0, start) + 1, text))
    return found


def template_files() -> list[Path]:
    return sorted(TEMPLATES.rglob("*.html"))


def module_files() -> list[Path]:
    return sorted(path for folder in MODULE_FOLDERS for path in folder.rglob("*.js")
                  if "i18n" not in path.relative_to(ROOT / "client_ui" / "static").parts[-2:][0]
                  and path.name != "i18n.js")


def untranslated() -> dict[str, list[tuple[int, str]]]:
    """Repository path -> its visible strings outside the catalogue."""
    found = {}
    for path in template_files():
        if strings := template_strings(path.read_text(encoding="utf-8")):
            found[str(path.relative_to(ROOT))] = strings
    for path in module_files():
        if strings := module_strings(path.read_text(encoding="utf-8")):
            found[str(path.relative_to(ROOT))] = strings
    return found


if __name__ == "__main__":
    for file, strings in untranslated().items():
        for line, text in strings:
            print(f"{file}:{line}: {text}")
    sys.exit(0)
