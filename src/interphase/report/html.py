"""The report's one HTML page (Jinja template templates/report/index.html.j2, autoescaped): a contents
list, links to every table (CSV, Markdown, LaTeX) and figure (PNG, PDF) by relative path, the figures
not drawn and why; styles inline, nothing fetched from outside, so the folder can be copied or zipped
as it is.

Layout: the page is as wide as the window (up to 1500 px); each inline table sits in its own box that
scrolls sideways if the table is wider (the page itself never does), cells of long text (notes) wrap
at a readable width so that the table fits where it can, and its notes follow it below."""

from __future__ import annotations

import hashlib
from pathlib import Path

import jinja2


def template_dir() -> Path:
    """templates/report shipped in the wheel (interphase/templates) or, in a checkout, ./templates."""
    packaged = Path(__file__).resolve().parents[1] / "templates" / "report"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[3] / "templates" / "report"


def template_hash() -> str:
    h = hashlib.sha256()
    for p in sorted(template_dir().glob("*.j2")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def render_page(path: Path, **context) -> Path:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(template_dir()), undefined=jinja2.StrictUndefined,
                             autoescape=jinja2.select_autoescape(["html", "j2"]))
    html = env.get_template("index.html.j2").render(**context)
    path.write_text(html, encoding="utf-8")
    return path


#: a cell with more characters than this wraps (class "long"); shorter ones stay on one line
LONG_CELL = 28


def _cell(v) -> str:
    from interphase.report.tables import _fmt

    return "–" if v is None or (isinstance(v, float) and v != v) else _fmt(v)


def html_table(df, notes=()) -> str:
    """`df` as an HTML table in a sideways-scrolling box (class "table-wrap"), its `notes` below;
    escaped. Numbers are right-aligned (class "num"), long text wraps (class "long")."""
    from html import escape

    from interphase.report.tables import _right_aligned

    right = [_right_aligned(df[c]) for c in df.columns]
    attr = lambda cls: f' class="{cls}"' if cls else ""
    head = "".join(f"<th{attr('num' if r else '')}>{escape(str(c))}</th>" for c, r in zip(df.columns, right))
    rows = []
    for row in df.itertuples(index=False):
        cells = []
        for v, r in zip(row, right):
            text = _cell(v)
            # a number stays on one line; a value with its interval may break before the bracket
            cls = ("num wrap" if " " in text else "num") if r else "long" if len(text) > LONG_CELL else ""
            cells.append(f"<td{attr(cls)}>{escape(text)}</td>")
        rows.append("<tr>" + "".join(cells) + "</tr>")
    note = "".join(f'<p class="tnote">{escape(n)}</p>' for n in notes)
    body = "".join(rows)
    return f'<div class="table-wrap"><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>{note}'
