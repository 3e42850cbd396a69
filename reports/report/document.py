"""The report's pages: collect sections, render HTML and Markdown.

A :class:`Document` is built top-down (``h``, ``p``, ``lead``, ``table``, ``image``,
``page``) and rendered twice from the same parts: HTML pages (a table of contents from
the level-1 headings, long tables folded in ``<details>``, pass and fail coloured) and
``report.md`` (the same tables as CommonMark pipe tables).  Figures are PNG files in
``img/``, which both refer to: the HTML loads them on demand (``loading="lazy"``, with
their pixel size, so that a page opens at once and keeps its layout), except those
marked ``eager`` (the first screen's).  ``page`` starts a page of its own (a case's
details, ``cases/<name>.html``): the HTML links it; the Markdown, one file, holds it in
place.  Every table is also written whole to ``<name>.csv`` and linked.  Every link is
relative to the page, so that the folder can be moved or zipped.
"""

from __future__ import annotations

import html
import re
import struct
from pathlib import Path

import numpy as np
import pandas as pd

#: Tables longer than this are folded (``<details>``) on the page.
FOLD_ROWS = 24

_MD_SPECIAL = re.compile(r"([\\`*_\[\]<>|#~!&])")
_MD_LINE_START = re.compile(r"^(\s*|\s*\d+)([-+=]|(?<=\d)[.)])")


def md_escape(text, block: bool = False) -> str:
    """Text as literal Markdown, as ``html.escape`` makes it literal HTML: the
    characters that start emphasis, code, links, tags, entities or table cells are
    backslash-escaped, and newlines (which would end a table row) become spaces.
    For a paragraph (``block``), a line-start list marker is escaped too."""
    s = _MD_SPECIAL.sub(r"\\\1", str(text).replace("\r", " ").replace("\n", " "))
    return _MD_LINE_START.sub(lambda m: m.group(1) + "\\" + m.group(2), s) if block else s


def file_stem(name: str) -> str:
    """A file-name-safe stem for ``name`` (a case may be a path such as sub/f.toml)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._") or "x"


def anchor(text: str) -> str:
    """An HTML id for a heading."""
    return "s-" + (re.sub(r"[^a-z0-9]+", "-", str(text).lower()).strip("-") or "x")


def drop_empty(df: pd.DataFrame) -> pd.DataFrame:
    """Without the columns that hold nothing (all NaN, None or empty strings)."""
    keep = []
    for c in df.columns:
        col = df[c]
        empty = col.isna() | col.astype(str).str.strip().isin(["", "None", "nan"])
        if not empty.all():
            keep.append(c)
    return df[keep]


_CSS = """
body{font-family:system-ui,sans-serif;max-width:1240px;margin:auto;padding:0 16px;
 color:#222;line-height:1.4}
h1.title{font-size:26px;margin:18px 0 4px}
h2{border-bottom:2px solid #ddd;padding-bottom:3px;margin-top:34px}
h3{margin-top:22px}
.card{border:1px solid #bbb;border-radius:8px;padding:10px 16px;background:#f8f9fb;
 display:flex;flex-wrap:wrap;gap:10px 36px;margin:10px 0}
.card div{min-width:150px}.card b{display:block;font-size:20px}
.card .big{font-size:15px}
nav.toc{column-count:3;font-size:14px;margin:8px 0 16px}
nav.toc a{display:block}
p.intro{background:#f4f6f8;border-left:4px solid #8aa;padding:6px 10px;font-size:14px}
table{border-collapse:collapse;font-size:12px;margin:8px 0;max-width:100%}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right;vertical-align:top}
th{background:#eef1f4;position:sticky;top:0}
td:first-child,th:first-child,td.text,th.text{text-align:left}
td.pass{background:#e3f4e3;color:#155d15;font-weight:bold}
td.fail{background:#fbe0e0;color:#a00;font-weight:bold}
td.wide{max-width:420px;text-align:left;font-size:11px;white-space:normal;word-break:break-word}
details{margin:6px 0}summary{cursor:pointer;color:#246}
.figs{display:flex;flex-wrap:wrap;gap:8px;align-items:flex-start}
figure{margin:0;flex:0 1 auto;max-width:calc(50% - 4px)}
figure:only-child{max-width:100%}
figure img{max-width:100%;height:auto;display:block}
figcaption{font-size:12px;color:#555}
.csv{font-size:12px}
.sub{color:#555;font-size:14px;margin:0 0 8px}
.lead{display:flex;flex-wrap:wrap;gap:12px 24px;align-items:flex-start;margin:6px 0 10px}
.lead .said{flex:1 1 440px;min-width:320px}
.lead .said p{margin:4px 0;font-size:15px}
.lead .said p.head{font-size:19px;font-weight:bold}
.lead ul{margin:4px 0 8px;padding-left:20px;font-size:13px}
.lead li{margin:2px 0}
.lead .fig{flex:0 1 640px;max-width:100%}
.lead .fig img{max-width:100%;height:auto;display:block}
.tag{font-weight:bold;padding:0 4px;border-radius:3px}
.tag.pass{background:#e3f4e3;color:#155d15}.tag.fail{background:#fbe0e0;color:#a00}
.tag.limit{background:#fdf0d5;color:#8a5300}
nav.links{font-size:14px;margin:6px 0}nav.links a{margin-right:14px}
ul.pages{columns:2;font-size:14px}
@media print{details{display:block}details>summary{display:none}nav.toc{display:none}
 table{font-size:9px}figure{break-inside:avoid}}
"""


def png_size(png: bytes) -> tuple[int, int] | None:
    """A PNG's pixel width and height (from its IHDR chunk), None if not a PNG."""
    if len(png) < 24 or png[:8] != b"\x89PNG\r\n\x1a\n" or png[12:16] != b"IHDR":
        return None
    return struct.unpack(">II", png[16:24])


class Document:
    """Collects sections; renders HTML pages and one Markdown file, figures as PNG files.

    ``page``: this page's path under ``out`` (``index.html``, ``cases/x.html``); links to
    files under ``out`` are written relative to it."""

    def __init__(self, out: Path, page: str = "index.html", _names: set | None = None):
        self.out = Path(out)
        self.page_path = page
        self.up = "../" * page.count("/")
        self.parts: list[tuple[str, object]] = []
        self.nimg = 0
        self._names = {page} if _names is None else _names  # every page name taken

    # ------------------------------------------------------------------ building
    def h(self, level: int, text: str):
        self.parts.append(("h", (level, text)))

    def p(self, text: str, intro: bool = False):
        """A paragraph; ``intro``: the short text at a section's head saying what it
        shows and how to read it."""
        self.parts.append(("intro" if intro else "p", text))

    def card(self, items: list[tuple[str, str]]):
        """A summary card: (label, value) pairs shown large, side by side."""
        self.parts.append(("card", items))

    def table(self, df: pd.DataFrame, name: str, caption: str = "", max_rows: int = 400,
              columns: list[str] | None = None, digits: int = 4,
              fold: int | None = FOLD_ROWS, wide: tuple[str, ...] = (),
              data: pd.DataFrame | None = None, whole: str | None = None):
        """Write the whole table to ``name.csv``; show ``columns`` (default all, empty
        ones dropped), numbers to ``digits`` significant figures, folded when longer
        than ``fold`` rows; more than ``max_rows`` rows are left to the CSV.  ``wide``:
        columns of long text, set small and wrapped.  ``data``: what the CSV holds
        instead of ``df`` (e.g. raw numbers behind a table formatted for reading).
        ``whole``: the name of a table already written whole that this one is cut from
        (a case's rows on its page): linked, no CSV of its own."""
        if whole is not None:
            name = whole
        else:
            (df if data is None else data).to_csv(self.out / f"{file_stem(name)}.csv",
                                                   index=False)
        shown = df[[c for c in columns if c in df.columns]] if columns else df
        shown = drop_empty(shown) if len(shown) else shown
        truncated = len(shown) > max_rows
        if truncated:
            shown = shown.head(max_rows)
        folded = fold is not None and len(shown) > fold
        self.parts.append(("table", (shown, name, caption, digits, folded, truncated,
                                     len(df), tuple(wide))))

    def image(self, png: bytes, name: str, caption: str = "", eager: bool = False):
        """A figure, written to ``img/<name>.png``; ``eager``: loaded with the page
        (the first screen's), else when scrolled near."""
        (self.out / "img").mkdir(exist_ok=True)
        (self.out / "img" / f"{file_stem(name)}.png").write_bytes(png)
        self.parts.append(("img", (png, name, caption, eager)))

    def page(self, name: str, title: str, link: str, about: str = "") -> Document:
        """A page of its own, ``cases/<name>.html`` (made unique), linked here as
        ``link`` followed by ``about``; returns its :class:`Document` to fill.  In the
        Markdown it stands in place (its headings one level down)."""
        stem, k = file_stem(name), 2
        path = f"cases/{stem}.html"
        while path in self._names:
            path, k = f"cases/{stem}-{k}.html", k + 1
        self._names.add(path)
        sub = Document(self.out, path, self._names)
        self.parts.append(("page", (sub, title, link, about)))
        return sub

    def lead(self, head: str, lines: list[str], items: list[tuple[str, str, str]],
             figure: tuple[bytes, str, str] | None = None,
             links: list[tuple[str, str]] = ()):
        """The first screen: a ``head`` line, plain ``lines``, a list of ``items``
        ``(tag, tag class, text)`` (the runs that did not pass, with their reasons),
        ``figure`` (png, name, caption; loaded with the page) beside them, and ``links``
        ``(text, target)`` to the details (``#`` and a heading's text, or a file; none
        given: every level-1 heading, the page's contents)."""
        if figure is not None:
            (self.out / "img").mkdir(exist_ok=True)
            (self.out / "img" / f"{file_stem(figure[1])}.png").write_bytes(figure[0])
        self.parts.append(("lead", (head, list(lines), list(items), figure, list(links))))

    # ------------------------------------------------------------------ rendering
    @staticmethod
    def _fmt(v, digits: int = 4):
        if isinstance(v, bool | np.bool_):
            return "yes" if v else "no"
        if isinstance(v, float | np.floating):
            if not np.isfinite(v):
                return "inf" if v == np.inf else ("" if np.isnan(v) else str(v))
            return f"{v:.{digits}g}"
        if v is None:
            return ""
        return str(v)

    @staticmethod
    def _cls(col: str, s: str, wide: tuple[str, ...]) -> str:
        low = s.strip().lower()
        if col in ("verdict", "passed", "within tolerance") or col.startswith("verdict"):
            if low in ("pass", "yes", "true"):
                return "pass"
            if low in ("fail", "no", "false"):
                return "fail"
        if col in wide:
            return "wide"
        try:
            float(s)
        except ValueError:
            return "text"
        return ""

    def _anchors(self) -> dict[int, str]:
        """A unique id for each heading (part index -> id)."""
        out, seen = {}, set()
        for i, (kind, d) in enumerate(self.parts):
            if kind == "h":
                a, k = anchor(d[1]), 2
                while a in seen:
                    a, k = f"{anchor(d[1])}-{k}", k + 1
                seen.add(a)
                out[i] = a
        return out

    def _toc(self) -> str:
        ids = self._anchors()
        links = [f"<a href='#{ids[i]}'>{html.escape(d[1])}</a>"
                 for i, (kind, d) in enumerate(self.parts) if kind == "h" and d[0] == 1]
        return "<nav class='toc'>" + "".join(links) + "</nav>" if links else ""

    def _target(self, target: str) -> str:
        """A link target: ``#Heading text`` -> that heading's id on this page; a file
        under ``out`` -> relative to this page."""
        if target.startswith("#"):
            ids = self._anchors()
            for i, (kind, d) in enumerate(self.parts):
                if kind == "h" and d[1] == target[1:]:
                    return "#" + ids[i]
            return "#" + anchor(target[1:])
        return self.up + target

    def _img_html(self, png: bytes, name: str, cap: str, eager: bool,
                  shown: bool = True) -> str:
        """A figure; ``shown``: with its caption under it (else the caption is the
        image's alternative text only)."""
        size = png_size(png)
        wh = f" width='{size[0]}' height='{size[1]}'" if size else ""
        load = "" if eager else " loading='lazy'"
        under = f"<figcaption>{html.escape(cap)}</figcaption>" if shown and cap else ""
        return (f"<figure><img alt='{html.escape(cap or name)}'{load}{wh} "
                f"src='{self.up}img/{html.escape(file_stem(name))}.png'>{under}</figure>")

    def _lead_html(self, head, lines, items, figure, links) -> str:
        ids = self._anchors()
        said = [f"<p class='head'>{html.escape(head)}</p>"]
        said += [f"<p>{html.escape(x)}</p>" for x in lines]
        if items:
            said.append("<ul>" + "".join(
                f"<li><span class='tag {html.escape(cls)}'>{html.escape(tag)}</span> "
                f"{html.escape(text)}</li>" for tag, cls, text in items) + "</ul>")
        # the details: the links given, else every level-1 heading (the contents)
        hrefs = ([(x, self._target(t)) for x, t in links] if links else
                 [(d[1], "#" + ids[i]) for i, (kind, d) in
                  enumerate(self.parts) if kind == "h" and d[0] == 1])
        if hrefs:
            said.append("<nav class='links'>Details: " + "".join(
                f"<a href='{html.escape(h)}'>{html.escape(x)}</a>" for x, h in hrefs)
                + "</nav>")
        fig = ""
        if figure is not None:
            fig = "<div class='fig'>" + self._img_html(*figure, eager=True, shown=False) + "</div>"
        return "<div class='lead'><div class='said'>" + "".join(said) + "</div>" + fig + "</div>"

    def html(self, title: str, subtitle: str = "") -> str:
        """This page's HTML (its sub-pages: :meth:`write_html`)."""
        out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'>"
               "<meta name='viewport' content='width=device-width, initial-scale=1'>"
               f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"]
        if self.up:
            out.append(f"<nav class='links'><a href='{self.up}index.html'>report index</a>"
                       "</nav>")
        # a sub-page's own first heading is its title
        own = bool(self.up) and bool(self.parts) and self.parts[0][0] == "h" \
            and self.parts[0][1][0] == 1
        if not own:
            out.append(f"<h1 class='title'>{html.escape(title)}</h1>")
        if subtitle:
            out.append(f"<p class='sub'>{html.escape(subtitle)}</p>")
        toc_done = any(kind == "lead" for kind, _ in self.parts)  # the lead links them
        ids = self._anchors()
        group = None  # consecutive figures share a flex row; consecutive pages a list
        for i, (kind, data) in enumerate(self.parts):
            if group and kind != group:
                out.append("</div>" if group == "img" else "</ul>")
                group = None
            if kind in ("img", "page") and group is None:
                out.append("<div class='figs'>" if kind == "img" else "<ul class='pages'>")
                group = kind
            if kind == "h":
                lv, text = data
                if lv == 1 and not toc_done and not self.up:
                    out.append("<h3>Contents</h3>" + self._toc())
                    toc_done = True
                tag = "h1 class='title'" if own and i == 0 else f"h{lv + 1}"
                out.append(f"<{tag} id='{ids[i]}'>{html.escape(text)}</{tag.split()[0]}>")
            elif kind == "p":
                out.append(f"<p>{html.escape(data)}</p>")
            elif kind == "intro":
                out.append(f"<p class='intro'>{html.escape(data)}</p>")
            elif kind == "card":
                cells = "".join(f"<div>{html.escape(k)}<b class='big'>{html.escape(v)}</b></div>"
                                for k, v in data)
                out.append(f"<div class='card'>{cells}</div>")
            elif kind == "lead":
                out.append(self._lead_html(*data))
            elif kind == "table":
                out.append(self._html_table(*data))
            elif kind == "img":
                out.append(self._img_html(*data))
            elif kind == "page":
                sub, _, link, about = data
                out.append(f"<li><a href='{html.escape(self.up + sub.page_path)}'>"
                           f"{html.escape(link)}</a>"
                           + (f" {html.escape(about)}" if about else "") + "</li>")
        if group:
            out.append("</div>" if group == "img" else "</ul>")
        out.append("</body></html>")
        return "\n".join(out)

    def subpages(self) -> list[Document]:
        """Every page this one links with :meth:`page`, depth first."""
        out = []
        for kind, data in self.parts:
            if kind == "page":
                out += [data[0], *data[0].subpages()]
        return out

    def write_html(self, title: str, subtitle: str = "") -> None:
        """Write this page and its sub-pages (each titled as :meth:`page` named it)."""
        (self.out / self.page_path).parent.mkdir(parents=True, exist_ok=True)
        (self.out / self.page_path).write_text(self.html(title, subtitle))
        for kind, data in self.parts:
            if kind == "page":
                data[0].write_html(data[1])

    def _html_table(self, df, name, cap, digits, folded, truncated, total, wide) -> str:
        cols = [str(c) for c in df.columns]
        head = "".join(f"<th class='{'text' if self._cls(c, 'x', wide) == 'text' else ''}'>"
                       f"{html.escape(c)}</th>" for c in cols)
        body = []
        for row in df.itertuples(index=False):
            cells = []
            for c, v in zip(cols, row, strict=True):
                s = self._fmt(v, digits)
                cells.append(f"<td class='{self._cls(c, s, wide)}'>{html.escape(s)}</td>")
            body.append("<tr>" + "".join(cells) + "</tr>")
        csv = (f"<p class='csv'>Full data: <a href='{self.up}{html.escape(file_stem(name))}"
               f".csv'>{html.escape(file_stem(name))}.csv</a>"
               + (f" ({total} rows; the first {len(df)} shown)" if truncated else "") + "</p>")
        cap_html = f"<caption>{html.escape(cap)}</caption>" if cap and not folded else ""
        table = f"<table id='{html.escape(name)}'>{cap_html}<tr>{head}</tr>{''.join(body)}</table>"
        if folded:
            return (f"<details><summary>{html.escape(cap or name)}: {len(df)} rows "
                    f"(click to show)</summary>{table}</details>{csv}")
        return table + csv

    def markdown(self, title: str) -> str:
        """The whole report as one Markdown file (sub-pages in place), beside ``img/``."""
        return "\n".join([f"# {md_escape(title)}", "", *self._md_parts(0)])

    def _md_parts(self, shift: int) -> list[str]:
        out: list[str] = []
        for kind, data in self.parts:
            if kind == "h":
                lv, text = data
                out += ["#" * (lv + 1 + shift) + " " + md_escape(text), ""]
            elif kind in ("p", "intro"):
                out += [md_escape(data, block=True), ""]
            elif kind == "card":
                out += [f"- **{md_escape(k)}:** {md_escape(v)}" for k, v in data] + [""]
            elif kind == "lead":
                out += self._md_lead(*data)
            elif kind == "table":
                out += self._md_table(*data)
            elif kind == "img":
                out += [f"![{md_escape(data[2])}](img/{file_stem(data[1])}.png)", ""]
            elif kind == "page":
                out += data[0]._md_parts(shift + 1)
        return out

    @staticmethod
    def _md_lead(head, lines, items, figure, links) -> list[str]:
        out = [f"**{md_escape(head)}**", ""]
        out += [x for line in lines for x in (md_escape(line, block=True), "")]
        out += [f"- **{md_escape(tag)}** {md_escape(text)}" for tag, _, text in items]
        out += [""] if items else []
        if figure is not None:
            out += [f"![{md_escape(figure[2])}](img/{file_stem(figure[1])}.png)", ""]
        return out

    def _md_table(self, df, name, cap, digits, folded, truncated, total, _wide) -> list[str]:
        out = []
        if folded:
            out += [f"<details><summary>{html.escape(cap or name)}: {len(df)} rows"
                    "</summary>", ""]
        elif cap:
            out += [f"*{md_escape(cap)}*", ""]
        out.append("| " + " | ".join(md_escape(c) for c in df.columns) + " |")
        out.append("|" + "---|" * len(df.columns))
        for row in df.itertuples(index=False):
            out.append("| " + " | ".join(md_escape(self._fmt(v, digits)) for v in row) + " |")
        out.append("")
        if folded:
            out += ["</details>", ""]
        more = f" ({total} rows; the first {len(df)} shown)" if truncated else ""
        out += [f"Full data: [{md_escape(name)}.csv]({file_stem(name)}.csv){more}", ""]
        return out


__all__ = ["Document", "FOLD_ROWS", "anchor", "drop_empty", "file_stem", "md_escape",
           "png_size"]
