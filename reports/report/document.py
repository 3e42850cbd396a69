"""The report page: collects sections, renders self-contained HTML and Markdown.

A :class:`Document` is built top-down (``h``, ``p``, ``card``, ``table``, ``image``) and
rendered twice from the same parts: ``index.html`` (images embedded, a table of
contents from the level-1 headings, long tables folded in ``<details>``, pass and fail
coloured) and ``report.md`` (the same tables as CommonMark pipe tables, images as PNG
files in ``img/``).  Every table is also written whole to ``<name>.csv`` and linked.
"""

from __future__ import annotations

import base64
import html
import re
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
@media print{details{display:block}details>summary{display:none}nav.toc{display:none}
 table{font-size:9px}figure{break-inside:avoid}}
"""


class Document:
    """Collects sections; renders self-contained HTML and Markdown with PNG files."""

    def __init__(self, out: Path):
        self.out = Path(out)
        self.parts: list[tuple[str, object]] = []
        self.nimg = 0

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
              data: pd.DataFrame | None = None):
        """Write the whole table to ``name.csv``; show ``columns`` (default all, empty
        ones dropped), numbers to ``digits`` significant figures, folded when longer
        than ``fold`` rows; more than ``max_rows`` rows are left to the CSV.  ``wide``:
        columns of long text, set small and wrapped.  ``data``: what the CSV holds
        instead of ``df`` (e.g. raw numbers behind a table formatted for reading)."""
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

    def image(self, png: bytes, name: str, caption: str = ""):
        (self.out / "img").mkdir(exist_ok=True)
        (self.out / "img" / f"{file_stem(name)}.png").write_bytes(png)
        self.parts.append(("img", (png, name, caption)))

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

    def html(self, title: str) -> str:
        out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
               f"</title><style>{_CSS}</style></head><body>"
               f"<h1 class='title'>{html.escape(title)}</h1>"]
        toc_done = False
        ids = self._anchors()
        in_figs = False
        for i, (kind, data) in enumerate(self.parts):
            if kind == "img" and not in_figs:  # consecutive figures share a flex row
                out.append("<div class='figs'>")
                in_figs = True
            elif kind != "img" and in_figs:
                out.append("</div>")
                in_figs = False
            if kind == "h":
                lv, text = data
                if lv == 1 and not toc_done:
                    out.append("<h3>Contents</h3>" + self._toc())
                    toc_done = True
                out.append(f"<h{lv + 1} id='{ids[i]}'>{html.escape(text)}</h{lv + 1}>")
            elif kind == "p":
                out.append(f"<p>{html.escape(data)}</p>")
            elif kind == "intro":
                out.append(f"<p class='intro'>{html.escape(data)}</p>")
            elif kind == "card":
                cells = "".join(f"<div>{html.escape(k)}<b class='big'>{html.escape(v)}</b></div>"
                                for k, v in data)
                out.append(f"<div class='card'>{cells}</div>")
            elif kind == "table":
                out.append(self._html_table(*data))
            elif kind == "img":
                png, name, cap = data
                b64 = base64.b64encode(png).decode()
                out.append(f"<figure><img alt='{html.escape(cap or name)}' "
                           f"src='data:image/png;base64,{b64}'><figcaption>"
                           f"{html.escape(cap)}</figcaption></figure>")
        if in_figs:
            out.append("</div>")
        out.append("</body></html>")
        return "\n".join(out)

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
        csv = (f"<p class='csv'>Full data: <a href='{html.escape(file_stem(name))}.csv'>"
               f"{html.escape(file_stem(name))}.csv</a>"
               + (f" ({total} rows; the first {len(df)} shown)" if truncated else "") + "</p>")
        cap_html = f"<caption>{html.escape(cap)}</caption>" if cap and not folded else ""
        table = f"<table id='{html.escape(name)}'>{cap_html}<tr>{head}</tr>{''.join(body)}</table>"
        if folded:
            return (f"<details><summary>{html.escape(cap or name)}: {len(df)} rows "
                    f"(click to show)</summary>{table}</details>{csv}")
        return table + csv

    def markdown(self, title: str) -> str:
        out = [f"# {md_escape(title)}", ""]
        for kind, data in self.parts:
            if kind == "h":
                lv, text = data
                out += ["#" * (lv + 1) + " " + md_escape(text), ""]
            elif kind in ("p", "intro"):
                out += [md_escape(data, block=True), ""]
            elif kind == "card":
                out += [f"- **{md_escape(k)}:** {md_escape(v)}" for k, v in data] + [""]
            elif kind == "table":
                df, name, cap, digits, folded, truncated, total, _ = data
                if folded:
                    out += [f"<details><summary>{html.escape(cap or name)}: {len(df)} rows"
                            "</summary>", ""]
                elif cap:
                    out += [f"*{md_escape(cap)}*", ""]
                out.append("| " + " | ".join(md_escape(c) for c in df.columns) + " |")
                out.append("|" + "---|" * len(df.columns))
                for row in df.itertuples(index=False):
                    out.append("| " + " | ".join(md_escape(self._fmt(v, digits))
                                                 for v in row) + " |")
                out.append("")
                if folded:
                    out += ["</details>", ""]
                more = f" ({total} rows; the first {len(df)} shown)" if truncated else ""
                out += [f"Full data: [{md_escape(name)}.csv]({file_stem(name)}.csv){more}", ""]
            elif kind == "img":
                _, name, cap = data
                out += [f"![{md_escape(cap)}](img/{file_stem(name)}.png)", ""]
        return "\n".join(out)


__all__ = ["Document", "FOLD_ROWS", "anchor", "drop_empty", "file_stem", "md_escape"]
