"""A self-contained HTML page: figures embedded as base64 PNG, tables inline, no external resource."""

from __future__ import annotations

import base64
import html
from pathlib import Path

import numpy as np
import pandas as pd

_CSS = """
body{font-family:-apple-system,Segoe UI,Helvetica,Arial,sans-serif;max-width:1180px;margin:2em auto;padding:0 1em;
color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em}h2{margin-top:2em;border-bottom:1px solid #ccc;padding-bottom:.2em}
table{border-collapse:collapse;font-size:.86em;margin:.6em 0}th,td{border:1px solid #ddd;padding:3px 7px;text-align:left}
th{background:#f3f3f3}td.num{text-align:right;font-variant-numeric:tabular-nums}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
figcaption{font-size:.9em;color:#444;margin-top:.4em}
.warn{background:#fff4e5;border-left:5px solid #e69f00;padding:.6em 1em;margin:1em 0}
.missing{background:#eef4fb;border-left:5px solid #0072b2;padding:.6em 1em;margin:1em 0}
.statement{background:#f1f8f4;border-left:5px solid #009e73;padding:.6em 1em;margin:1em 0}
.meta{color:#555;font-size:.9em}code{background:#f6f6f6;padding:0 3px}
nav a{margin-right:1em}
"""


class Page:
    """Sections appended in order; :meth:`write` produces one HTML file."""

    def __init__(self, title: str):
        self.title = title
        self.parts: list[str] = []
        self.toc: list[tuple[str, str]] = []

    def section(self, anchor: str, heading: str) -> None:
        self.toc.append((anchor, heading))
        self.parts.append(f'<h2 id="{anchor}">{html.escape(heading)}</h2>')

    def paragraph(self, text: str) -> None:
        self.parts.append(f"<p>{html.escape(text)}</p>")

    def raw(self, fragment: str) -> None:
        self.parts.append(fragment)

    def box(self, kind: str, title: str, items: list[str]) -> None:
        """A highlighted list (``kind`` ``"warn"``, ``"missing"`` or ``"statement"``)."""
        if items:
            lis = "".join(f"<li>{html.escape(i)}</li>" for i in items)
            self.parts.append(f'<div class="{kind}"><strong>{html.escape(title)}</strong><ul>{lis}</ul></div>')

    def figure(self, png: Path, caption: str, alt: str) -> None:
        data = base64.b64encode(Path(png).read_bytes()).decode("ascii")
        self.parts.append(f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">'
                          f"<figcaption><strong>{html.escape(Path(png).name)}.</strong> {html.escape(caption)}"
                          "</figcaption></figure>")

    def table(self, df: pd.DataFrame, digits: int | dict[str, int] = 2, index: bool = True) -> None:
        """An HTML table; numbers right-aligned with ``digits`` decimals (per column if a dict)."""
        if index:
            df = df.reset_index()
        ncols = {c: (digits.get(c, 2) if isinstance(digits, dict) else digits) for c in df.columns}

        def cell(v, c):
            if v is None or (isinstance(v, float) and v != v) or v is pd.NA:
                return '<td class="num">—</td>'
            if isinstance(v, (bool, np.bool_)):
                return f"<td>{'yes' if v else 'no'}</td>"
            if isinstance(v, (int, np.integer)):
                return f'<td class="num">{v}</td>'
            if isinstance(v, (float, np.floating)):
                return f'<td class="num">{v:.{ncols[c]}f}</td>'
            return f"<td>{html.escape(str(v))}</td>"

        head = "".join(f"<th>{html.escape(str(c))}</th>" for c in df.columns)
        body = "".join("<tr>" + "".join(cell(v, c) for v, c in zip(row, df.columns)) + "</tr>"
                       for row in df.itertuples(index=False))
        self.parts.append(f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")

    def write(self, path: Path, meta: str) -> None:
        nav = " ".join(f'<a href="#{a}">{html.escape(h)}</a>' for a, h in self.toc)
        body = "\n".join(self.parts)
        Path(path).write_text(
            f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{html.escape(self.title)}</title>"
            f"<style>{_CSS}</style></head><body><h1>{html.escape(self.title)}</h1>"
            f"<p class=\"meta\">{html.escape(meta)}</p><nav>{nav}</nav>\n{body}\n</body></html>\n",
            encoding="utf-8")
