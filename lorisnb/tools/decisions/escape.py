"""Text received from others (a folder name, a label, a value read from a run.json or a table) made
harmless for each output that shows it, by one rule: :func:`clean`. A character that is not
printable (a control character: ESC of an escape sequence, a newline, a carriage return, a tab;
a bidirectional override such as U+202E; a lone surrogate of a name that is not UTF-8) is shown
escaped as Python writes it (``\\x1b``, ``\\n``, ``\\t``, ``\\u202e``), and so is a backslash
(``\\\\``, as Python's ``repr`` and ``ls -b`` show it: a folder literally named ``orb\\x1b`` and
one named ``orb`` + ESC never print the same): a name reads the same in the terminal, in Markdown,
in GitHub's annotations, in JUnit XML and in figures, two different names never print the same
(the rule is one-to-one), and nothing in them acts (moves the cursor, reverses a line, ends a row,
a command or an XML file's well-formedness: XML 1.0 allows no C0 control but tab, newline and
carriage return).

Each format then escapes its own syntax: :func:`markdown_cell` and :func:`code_span` (Markdown),
:func:`workflow_data` and :func:`workflow_property` (GitHub's workflow commands, as its runner
decodes them); XML writers pass every attribute and text through :func:`clean` and let the XML
library escape ``&``, ``<`` and quotes. JSON, CSV and Parquet keep the text whole (their own
quoting holds any character), so that a name read back is the name written."""

from __future__ import annotations


def clean(text: object) -> str:
    """Text for one terminal line (or one XML attribute, one cell, one figure label): characters
    that are not printable shown escaped, as ``\\n``, ``\\x1b`` or ``\\u202e``, and a backslash as
    ``\\\\``, so that tables and lists keep their lines, the terminal interprets nothing in them
    and two different texts never show the same. Applied once to a name: its result is shown, never
    escaped again (a backslash it wrote would be doubled)."""
    s = str(text)
    if s.isprintable() and "\\" not in s:
        return s
    return "".join(c if c.isprintable() and c != "\\" else _escaped(c) for c in s)


def message_line(text: object) -> str:
    """Text for one message line (``error: ...``, ``warning: ...``, ``note: ...``): as :func:`clean`,
    except that a backslash shows as itself. A message quotes values as Python writes them
    (``'a\\tb'``: already escaped) and the user's own text as typed (``--trials-by 'seed(\\d+)'``,
    an example to copy), which a second escape would garble; its control characters are escaped
    all the same, so it stays one line and the terminal acts on nothing in it. Names are told apart
    where they are listed (tables, verdict lines, :func:`clean`)."""
    s = str(text)
    return s if s.isprintable() else "".join(c if c.isprintable() else _escaped(c) for c in s)


def _escaped(c: str) -> str:
    return c.encode("unicode_escape").decode("ascii")


#: Characters Markdown gives a meaning inside a line (a table's cell border, code, emphasis, a link,
#: strike-through), escaped with a backslash so that a name shows as it is. Not ``_``: the most common
#: character of a name (``orbslam2_rgbd``) makes no emphasis inside a word.
_MARKDOWN_PUNCTUATION = "\\|`*[]~"


def markdown_cell(text: object) -> str:
    """Text for a Markdown table cell or line (GitHub-flavoured): :func:`clean`, then Markdown's
    punctuation escaped with a backslash and ``&``, ``<``, ``>`` as HTML entities (no tag, no
    link, no emphasis made of a name)."""
    s = "".join("\\" + c if c in _MARKDOWN_PUNCTUATION else c for c in clean(text))
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def code_span(text: object) -> str:
    """Text as a Markdown code span (shown as it is, in a fixed-width font; not in a table, whose
    ``|`` it would end): :func:`clean`, between as many backticks as it needs (one more than its
    longest run of backticks)."""
    s = clean(text)
    run = longest = 0
    for c in s:
        run = run + 1 if c == "`" else 0
        longest = max(longest, run)
    fence = "`" * (longest + 1)
    pad = " " if s.startswith("`") or s.endswith("`") or (s[:1] == s[-1:] == " " and s.strip()) else ""
    return f"{fence}{pad}{s}{pad}{fence}"


def workflow_data(text: object) -> str:
    """Text for the message of a GitHub workflow command (``::error ...::MESSAGE``): :func:`clean`,
    then GitHub's own encoding of ``%``, carriage return and newline (``%25``, ``%0D``, ``%0A``)."""
    return clean(text).replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def workflow_property(text: object) -> str:
    """Text for a property of a GitHub workflow command (``title=...``): :func:`workflow_data`, and
    ``:`` and ``,`` (which end a property) as ``%3A`` and ``%2C``."""
    return workflow_data(text).replace(":", "%3A").replace(",", "%2C")
