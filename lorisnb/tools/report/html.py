"""HTML that opens offline: notebook pages exported by nbconvert without any script from a CDN
(no require.js, MathJax, Mermaid or widget manager; the notebooks have no TeX), code cells folded
away under a "code" toggle, progress bars dropped and other widgets replaced by their text or by a
note; and ``report.html``, the front page with every image and style inlined, for e-mail.
"""

from __future__ import annotations

import base64
import functools
import mimetypes
import re
import sys
import warnings
from pathlib import Path
from typing import Any

from lorisnb.errors import LorisWarning
from lorisnb.io.writers import naming, write_text
from lorisnb.tools._extras import require

#: The notebook template: nbconvert's ``lab`` template without remote scripts, code folded.
TEMPLATE = "lorisnb_offline.html.j2"
_TEMPLATE_TEXT = r"""{%- extends 'index.html.j2' -%}
{%- block html_head_js_requirejs -%}{%- endblock html_head_js_requirejs -%}
{% block jupyter_widgets %}{% endblock jupyter_widgets %}
{%- block html_head_js_mathjax -%}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
{% block extra_css %}<style>details.lorisnb-code>summary{cursor:pointer;color:#666;font:12px sans-serif;
margin:2px 0 2px 70px}.lorisnb-note{color:#666;font-style:italic}</style>{% endblock extra_css %}
{% block notebook_css %}
{%- if resources.lorisnb_css -%}<link rel="stylesheet" href="{{ resources.lorisnb_css }}">{%- else -%}{{ super() }}{%- endif -%}
{% endblock notebook_css %}
{% block input_group -%}
<details class="lorisnb-code"><summary>code</summary>
{{ super() }}
</details>
{%- endblock input_group %}
"""

WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
WIDGET_NOTE = "[interactive widget: open the .ipynb beside this page in Jupyter to use it]"
_WIDGET_REPR = re.compile(r"^[A-Za-z_]\w*\(")  # 'VBox(children=...)': a widget's repr, not a text
_PROGRESS = re.compile(r"\d+%\|")  # a tqdm bar's text as first shown (0%): nothing to keep after the run


def _template_dirs() -> list[str]:
    """nbconvert's own templates, also when it is installed in another environment than
    ``sys.prefix`` (a venv layered on another)."""
    nbconvert = require("nbconvert")
    here = Path(str(nbconvert.__file__)).resolve()
    dirs = [Path(sys.prefix) / "share" / "jupyter" / "nbconvert" / "templates"]
    dirs += [p / "share" / "jupyter" / "nbconvert" / "templates" for p in here.parents[:5]]
    return [str(d) for d in dict.fromkeys(dirs) if (d / "lab").is_dir()]


def static_widgets(nb: Any) -> Any:
    """Drop the widget state and replace each widget output by its text (tqdm bars print their
    last state) or by :data:`WIDGET_NOTE`; returns the notebook, changed in place."""
    nb.metadata.pop("widgets", None)
    for cell in nb.cells:
        kept = []
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            if WIDGET_VIEW in data:
                text = str(data.get("text/plain", ""))
                if _PROGRESS.search(text):
                    continue
                out["data"] = {"text/plain": WIDGET_NOTE if not text or _WIDGET_REPR.match(text) else text}
            kept.append(out)
        if "outputs" in cell:
            cell["outputs"] = kept
    return nb


#: Rules of nbconvert's lab template that sit outside its style sheets.
_EXTRA_CSS = """
* { -webkit-print-color-adjust: exact; }
a.anchor-link { display: none; }
.jp-InputArea { overflow: hidden; }
.jp-InputArea-editor { overflow: hidden; }
.cm-editor.cm-s-jupyter .highlight pre { padding: var(--jp-code-padding) 4px; margin: 0; font-family: inherit;
  font-size: inherit; line-height: inherit; color: inherit; }
.jp-OutputArea-output pre { line-height: inherit; font-family: inherit; }
.jp-RenderedText pre { color: var(--jp-content-font-color1); font-size: var(--jp-code-font-size); }
.jp-Collapser { display: none; }
"""


def write_notebook_css(out: Path) -> Path:
    """The style sheet of nbconvert's lab template (light theme) as one file, which every notebook
    page of a run links (:func:`export_html` with ``css``) instead of carrying its own copy."""
    static = Path(_template_dirs()[0]) / "lab" / "static"
    text = "\n".join((static / name).read_text(encoding="utf-8") for name in ("index.css", "theme-light.css"))
    with naming(out):  # a full disk names the file
        out.write_text(text + _EXTRA_CSS, encoding="utf-8")
    return out


def export_html(ipynb: Path, css: str | None = None, out: Path | None = None) -> Path:
    """The notebook ``ipynb`` as an offline HTML page beside it (same stem), or as ``out``; raises on
    failure. ``css``: a style sheet to link (a relative URL, see :func:`write_notebook_css`) instead of
    inlining nbconvert's (about 280 kB per page). Written whole or not at all
    (:func:`~lorisnb.io.writers.write_text`: a full disk leaves the page as it was, and names it)."""
    nbformat = require("nbformat")

    nb = static_widgets(nbformat.read(str(ipynb), as_version=4))
    resources = {"metadata": {"name": ipynb.stem}, "lorisnb_css": css or ""}
    body, _ = _exporter().from_notebook_node(nb, resources=resources)
    return write_text(body, out if out is not None else ipynb.with_suffix(".html"), force=True)


@functools.lru_cache(maxsize=1)
def _exporter() -> Any:
    """nbconvert's HTML exporter with lorisnb's template, made once per process: its templates are
    compiled at the first page and reused by the next (as nbconvert's own command does for several
    notebooks); each page's lexer and widget state are set per page by nbconvert."""
    nbconvert = require("nbconvert")
    jinja2 = require("jinja2")

    return nbconvert.HTMLExporter(
        template_name="lab",
        template_file=TEMPLATE,
        extra_loaders=[jinja2.DictLoader({TEMPLATE: _TEMPLATE_TEXT})],
        extra_template_basedirs=_template_dirs(),
        extra_template_paths=_template_dirs(),
    )


_SRC = re.compile(r"""(<img\b[^>]*?\bsrc=)(['"])([^'"]+)\2""", re.IGNORECASE)
_HREF = re.compile(r"""<a\b[^>]*?\bhref=(['"])([^'"#]+)\1[^>]*>(.*?)</a>""", re.IGNORECASE | re.DOTALL)


def single_file(index: Path, out: Path) -> Path:
    """``out``: the page ``index`` with every local image inlined (data: URIs) and links to the
    run folder's other files turned into their names (they are not in the single file). No
    other file is needed to read it."""
    root = index.parent
    text = index.read_text(encoding="utf-8")
    lost: list[str] = []

    def inline(m: re.Match[str]) -> str:
        src = m.group(3)
        path = root / src
        inside = root.resolve() in path.resolve().parents  # nothing outside the run folder is read into it
        if src.startswith(("data:", "http:", "https:")) or not inside or not path.is_file():
            if inside and not src.startswith(("data:", "http:", "https:")) and not path.exists():
                lost.append(src)
            return m.group(0)
        kind = mimetypes.guess_type(path.name)[0] or "application/octet-stream"
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        return f"{m.group(1)}{m.group(2)}data:{kind};base64,{data}{m.group(2)}"

    def unlink(m: re.Match[str]) -> str:
        href = m.group(2)
        if href.startswith(("http:", "https:", "mailto:")):
            return m.group(0)
        return f"<span title='in the run folder: {href}'>{m.group(3)}</span>"

    text = _SRC.sub(inline, text)
    text = _HREF.sub(unlink, text)
    if lost:  # the one file to send would show a broken image without a word
        shown = ", ".join(lost[:5]) + (f" and {len(lost) - 5} more" if len(lost) > 5 else "")
        warnings.warn(f"{index}: {len(lost)} figure(s) it shows are not in the run folder (lost in a copy?), so "
                      f"not in the single file made of it: {shown}", LorisWarning, stacklevel=2)  # fmt: skip
    return write_text(text, out, force=True)
