"""Write a worked solution as Markdown, HTML or LaTeX.

* Markdown: ``$...$`` / ``$$...$$`` LaTeX from SymPy's printer; each figure as an SVG
  file beside the output (or embedded as a data URI when printing to stdout).
* HTML: one self-contained page; mathematics as presentation MathML from SymPy's
  MathML printer (rendered by the browser itself, offline: no script, no network),
  figures as inline SVG.
* LaTeX: a standalone ``article``; figures as TikZ.

A substituted equation is followed by its ``calc:`` line, the plain-text form of
the same SymPy expression and the value it evaluates to.
"""

from __future__ import annotations

import base64
import html as _html
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from reports.explain import printing as P
from reports.explain.blocks import Document, Figure, Heading, Math, Para, Table


def _parts(parts, math, text) -> str:
    """Running text: strings through ``text``, expressions through ``math``."""
    if isinstance(parts, str):
        parts = [parts]
    return "".join(text(p) if isinstance(p, str) else math(p) for p in parts)


def _md_parts(parts) -> str:
    return _parts(parts, lambda e: f"${P.latex(e)}$", lambda s: s)


def _html_parts(parts) -> str:
    return _parts(parts, _ml, _html.escape)


def _tex_parts(parts) -> str:
    return _parts(parts, lambda e: f"${P.latex(e)}$", _tex_text)


def _calc(b: Math) -> str:
    return f"calc: {b.check} = {b.value}"


def _unit_tex(u: str) -> str:
    u = u.replace("^2", "²")
    return r"\ \mathrm{{{}}}".format(u.replace("²", "^2").replace("deg", r"{}^\circ")) if u else ""


def _sci(value: str) -> tuple[str, str | None]:
    """A printed value split as mantissa and power of ten (``6.73338e-13`` ->
    ``('6.73338', '-13')``; ``None`` without an exponent)."""
    m, _, e = value.partition("e")
    return (m, str(int(e))) if e else (value, None)


def _value_tex(value: str) -> str:
    m, e = _sci(value)
    return m if e is None else rf"{m} \cdot 10^{{{e}}}"


def _value_ml(value: str) -> str:
    m, e = _sci(value)
    if e is None:
        return f"<mn>{m}</mn>"
    return (f"<mn>{m}</mn><mo>\u22c5</mo><msup><mn>10</mn><mn>{e.replace('-', chr(0x2212))}"
            "</mn></msup>")


def _chain_tex(b: Math) -> str:
    parts = [P.latex(p) for p in b.parts]
    if b.value is not None:
        v = _value_tex(b.value) + (r"^\circ" if b.unit == "deg" else _unit_tex(b.unit))
        parts.append(v)
    if len(parts) <= 2:
        return " = ".join(parts)
    return (r"\begin{aligned} " + parts[0] + " &= " + r" \\ &= ".join(parts[1:])
            + r" \end{aligned}")


def _cell_md(c) -> str:
    if isinstance(c, str):
        return c.replace("|", "\\|")
    return f"${P.latex(c)}$"


def _numbers(doc: Document) -> dict[int, int]:
    """Tables numbered in order (``Table 3``), as a reader refers to them; the key
    (``variables1-1``) stays the anchor a link or a test finds the table by."""
    tables = [b for b in doc.blocks if isinstance(b, Table)]
    return {id(t): n for n, t in enumerate(tables, start=1)}


def to_markdown(doc: Document, figdir: Path | None = None, stem: str = "explain") -> str:
    out = [f"# {doc.title}", ""]
    num = _numbers(doc)
    for b in doc.blocks:
        if isinstance(b, Heading):
            out += ["#" * b.level + " " + b.text, ""]
        elif isinstance(b, Para):
            out += [_md_parts(b.parts), ""]
        elif isinstance(b, Math):
            out += ["$$", _chain_tex(b), "$$", ""]
            if b.note:
                out += [f"*{_md_parts(b.note)}*", ""]
            if b.check is not None:
                out += [f"`{_calc(b)}`", ""]
        elif isinstance(b, Table):
            out += [f'<a id="{b.key}"></a>*Table {num[id(b)]}: {b.caption}*', ""]
            out.append("| " + " | ".join(_cell_md(c) for c in b.header) + " |")
            out.append("|" + "---|" * len(b.header))
            for row in b.rows:
                out.append("| " + " | ".join(_cell_md(c) for c in row) + " |")
            out.append("")
        elif isinstance(b, Figure):
            if figdir is not None:
                name = f"{stem}-{b.name}.svg"
                (figdir / name).write_text(b.svg, encoding="utf-8")
                out += [f"![{b.caption}]({name})", ""]
            else:
                data = base64.b64encode(b.svg.encode()).decode()
                out += [f"![{b.caption}](data:image/svg+xml;base64,{data})", ""]
            out += [f"*{b.caption}*", ""]
    return "\n".join(out)


# -- HTML -----------------------------------------------------------------------------------

_CSS = """
body { font-family: Georgia, 'DejaVu Serif', serif; max-width: 1100px; margin: 2em auto;
       padding: 0 1em; color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
math[display=block] { display: block; margin: 0.6em 0; font-size: 1.1em; }
.eq { overflow-x: auto; overflow-y: hidden; padding: 0.2em 0; }
p.caption { font-style: italic; margin: 1em 0 0.2em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; }
td, th { border: 1px solid #bbb; padding: 0.25em 0.7em; text-align: right; }
code.calc { display: block; color: #555; font-size: 0.85em; margin: -0.2em 0 0.8em 1em; }
.note { color: #555; font-style: italic; margin: -0.3em 0 0.6em 1em; }
figure { margin: 1em 0; } figcaption { font-style: italic; color: #444; }
"""


def _ml(e, display: bool = False) -> str:
    if isinstance(e, str):
        return _html.escape(e)
    d = ' display="block"' if display else ""
    return f'<math xmlns="http://www.w3.org/1998/Math/MathML"{d}>{P.mathml(e)}</math>'


def _chain_items(b: Math) -> list[str]:
    items = [P.mathml(p) for p in b.parts]
    if b.value is not None:
        unit = {"deg": "<mo>°</mo>"}.get(b.unit, f"<mspace width='0.3em'/><mtext>"
                                         f"{_html.escape(b.unit.replace('^2', '²'))}</mtext>"
                                         if b.unit else "")
        items.append(f"<mrow>{_value_ml(b.value)}{unit}</mrow>")
    return items


def _chain_rows(b: Math) -> list[str]:
    """The rows an equation is displayed in: one, or the first two parts and then one
    per further part (as :func:`_chain_ml` lays them out)."""
    items = _chain_items(b)
    if len(items) <= 2:
        return ["<mo>=</mo>".join(items)]
    return [items[0] + "<mo>=</mo>" + it for it in items[1:]]  # the left column, each row


def _chain_ml(b: Math) -> str:
    items = _chain_items(b)
    head = '<math xmlns="http://www.w3.org/1998/Math/MathML" display="block">'
    if len(items) <= 2:
        return f"{head}<mrow>{'<mo>=</mo>'.join(items)}</mrow></math>"
    # a chain: one '=' per row, aligned as LaTeX's aligned
    items = [f'<mrow displaystyle="true">{it}</mrow>' for it in items]
    rows = [f"<mtr><mtd style='text-align: right'>{items[0]}</mtd><mtd><mo>=</mo></mtd>"
            f"<mtd style='text-align: left'>{items[1]}</mtd></mtr>"]
    rows += [f"<mtr><mtd></mtd><mtd><mo>=</mo></mtd><mtd style='text-align: left'>{it}</mtd>"
             "</mtr>" for it in items[2:]]
    return f"{head}<mtable>{''.join(rows)}</mtable></math>"


_SCRIPT_SCALE = 0.7   # MathML's scriptlevel 1 size (a sub- or superscript, an under-label)
_GLYPH_EM = 0.55      # mean advance of a math glyph and its spacing, em (serif, measured)
_EQ_EM = 52.0         # the equation column (62 em of the maths at 1.1 em in 1100 px), less
                      # the estimate's error (up to 15 % short, measured in Chromium)


def _ml_width(el) -> float:
    """An estimate of a MathML element's width in glyphs: a fraction is as wide as its
    wider part, scripts count at script size, everything else side by side."""
    tag = el.tag
    kids = list(el)
    own = len((el.text or "").strip())
    if tag == "mfrac":
        return max((_ml_width(k) for k in kids), default=0.0)
    if tag in ("msub", "msup", "msubsup"):
        return _ml_width(kids[0]) + _SCRIPT_SCALE * sum(_ml_width(k) for k in kids[1:])
    if tag in ("munder", "mover", "munderover"):
        return max([_ml_width(kids[0])] + [_SCRIPT_SCALE * _ml_width(k) for k in kids[1:]])
    if tag == "mtable":   # rows one under another
        return max((_ml_width(k) for k in kids), default=0.0)
    return own + sum(_ml_width(k) for k in kids)


def _ml_tree(fragment: str):
    """A MathML fragment as an element tree; SymPy's named entities (the invisible
    times and function application, which take no width) dropped, others one glyph."""
    text = re.sub(r"&(InvisibleTimes|ApplyFunction|it|af);", "", fragment)
    return ET.fromstring("<r>" + re.sub(r"&[A-Za-z]+;", "x", text) + "</r>")


def _fit(rows: list[str]) -> str:
    """A style that shrinks a displayed equation to the column when its widest row
    would be wider (as LaTeX's ``\\resizebox`` in the tex format; MathML has no line
    breaking and the page no script), never below 60 %, where the text would be too
    small to read: such an equation (a long acceleration elimination of a second loop)
    scrolls in its own box."""
    try:
        width = max(_ml_width(_ml_tree(r)) for r in rows) * _GLYPH_EM
    except SyntaxError:   # ElementTree's ParseError: estimate nothing, shrink nothing
        return ""
    if width <= _EQ_EM:
        return ""
    return f' style="font-size: {max(60, int(100 * _EQ_EM / width))}%"'


def to_html(doc: Document) -> str:
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>{_html.escape(doc.title)}</title><style>{_CSS}</style></head><body>",
           f"<h1>{_html.escape(doc.title)}</h1>"]
    num = _numbers(doc)
    for b in doc.blocks:
        if isinstance(b, Heading):
            out.append(f"<h{b.level}>{_html.escape(b.text)}</h{b.level}>")
        elif isinstance(b, Para):
            out.append("<p>" + _html_parts(b.parts) + "</p>")
        elif isinstance(b, Math):
            out.append(f'<div class="eq"{_fit(_chain_rows(b))}>{_chain_ml(b)}</div>')
            if b.note:
                out.append(f'<p class="note">{_html_parts(b.note)}</p>')
            if b.check is not None:
                out.append(f'<code class="calc">{_html.escape(_calc(b))}</code>')
        elif isinstance(b, Table):
            out.append(f'<p class="caption">Table {num[id(b)]}: {_html.escape(b.caption)}'
                       f'</p><table id="{b.key}"><tr>'
                       + "".join(f"<th>{_ml(c)}</th>" for c in b.header) + "</tr>")
            for row in b.rows:
                out.append("<tr>" + "".join(f"<td>{_ml(c)}</td>" for c in row) + "</tr>")
            out.append("</table>")
        elif isinstance(b, Figure):
            out.append(f"<figure>{b.svg}<figcaption>{_html.escape(b.caption)}</figcaption>"
                       "</figure>")
    out.append("</body></html>")
    return "\n".join(out)


# -- LaTeX -----------------------------------------------------------------------------------

_TEX_TEXT = [("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("$", r"\$"),
             ("#", r"\#"), ("_", r"\_"), ("{", r"\{"), ("}", r"\}"), ("^", r"\^{}"),
             ("~", r"\~{}")]
_TEX_UNICODE = [("θ̇", r"$\dot\theta$"), ("θ̈", r"$\ddot\theta$"), ("ṙ", r"$\dot r$"),
                ("r̈", r"$\ddot r$"), ("ṡ", r"$\dot s$"), ("s̈", r"$\ddot s$"),
                ("θ", r"$\theta$"), ("μ", r"$\mu$"), ("σ", r"$\sigma$"), ("ω", r"$\omega$"),
                ("α", r"$\alpha$"), ("δ", r"$\delta$"), ("γ", r"$\gamma$"), ("°", r"$^\circ$"),
                ("²", r"$^2$"), ("−", "-"), ("·", r"$\cdot$"), ("→", r"$\to$"),
                ("∞", r"$\infty$"), ("≈", r"$\approx$"), ("×", r"$\times$"),
                ("Σ", r"$\Sigma$"), ("⟂", r"$\perp$")]


def _tex_text(s: str) -> str:
    for a, b in _TEX_TEXT:
        s = s.replace(a, b)
    for a, b in _TEX_UNICODE:
        s = s.replace(a, b)
    return s


def _tex_cell(c) -> str:
    return _tex_text(c) if isinstance(c, str) else f"${P.latex(c)}$"


def to_latex(doc: Document) -> str:
    out = [r"\documentclass[11pt]{article}", r"\usepackage[utf8]{inputenc}",
           r"\usepackage{amsmath,amssymb,graphicx}", r"\usepackage{tikz}",
           r"\usepackage[margin=2cm]{geometry}", r"\allowdisplaybreaks",
           r"\begin{document}", rf"\section*{{{_tex_text(doc.title)}}}"]
    num = _numbers(doc)
    for b in doc.blocks:
        if isinstance(b, Heading):
            out.append({2: r"\subsection*{%s}", 3: r"\subsubsection*{%s}"}.get(
                b.level, r"\paragraph{%s}") % _tex_text(b.text))
        elif isinstance(b, Para):
            out.append(_tex_parts(b.parts) + "\n")
        elif isinstance(b, Math):
            # shrunk to the line width when longer (graphicx's \width), never enlarged
            out.append(r"\[\resizebox{\ifdim\width>\linewidth\linewidth\else\width\fi}{!}"
                       r"{$\displaystyle " + _chain_tex(b) + r"$}\]")
            if b.note:
                out.append(r"{\small\itshape " + _tex_parts(b.note) + "}\n")
            if b.check is not None:
                out.append(r"{\footnotesize\texttt{" + _tex_text(_calc(b)) + "}}\n")
        elif isinstance(b, Table):
            out.append(r"\begin{center}{\small\itshape Table " + str(num[id(b)]) + ": "
                       + _tex_text(b.caption) + r"}\\[2pt]")
            out.append(r"\begin{tabular}{" + "|c" * len(b.header) + "|}\\hline")
            out.append(" & ".join(_tex_cell(c) for c in b.header) + r"\\\hline")
            for row in b.rows:
                out.append(" & ".join(_tex_cell(c) for c in row) + r"\\\hline")
            out.append(r"\end{tabular}\end{center}")
        elif isinstance(b, Figure):
            out.append(r"\begin{center}" + b.tikz + r"\\[2pt]{\small\itshape "
                       + _tex_text(b.caption) + r"}\end{center}")
    out.append(r"\end{document}")
    return "\n".join(out)


def render(doc: Document, fmt: str, out: Path | None = None) -> str:
    if fmt == "html":
        return to_html(doc)
    if fmt == "tex":
        return to_latex(doc)
    figdir = out.parent if out is not None else None
    return to_markdown(doc, figdir, out.stem if out is not None else "explain")
