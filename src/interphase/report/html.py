"""The report's one HTML page (Jinja template templates/report/index.html.j2, autoescaped): links to
every table (CSV, Markdown, LaTeX) and figure (PNG, PDF) by relative path; styles inline, nothing
fetched from outside, so the folder can be copied or zipped as it is."""

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
