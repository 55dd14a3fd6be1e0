"""A report as one self-contained HTML page: the Markdown tables as HTML tables, figures inline."""

from __future__ import annotations

import base64
import html

from vissim.validation.engine.figures import Figure

__all__ = ["html_report"]


def _inline(text: str) -> str:
    """A line of Markdown as HTML: escaped, ``code`` spans as <code>."""
    parts = html.escape(text).split("`")
    return "".join(f"<code>{part}</code>" if k % 2 else part for k, part in enumerate(parts))


def _html_block(block: str) -> list[str]:
    """One ``### `` section of the Markdown: its heading, paragraphs and table (if any)."""
    lines = [line for line in block.strip().splitlines() if line.strip()]
    parts, body = [f"<h2>{_inline(lines[0])}</h2>"], lines[1:]
    rows = [line for line in body if line.startswith("|") and not line.startswith("|---")]
    first = next((k for k, line in enumerate(body) if line.startswith("|")), len(body))
    before, after = ([t for t in part if not t.startswith("|")] for part in (body[:first], body[first:]))
    parts += [f"<p>{_inline(t)}</p>" for t in before]
    if rows:
        parts.append("<table>")
        for k, line in enumerate(rows):
            tag = "th" if k == 0 else "td"
            cells = [c.strip() for c in line.strip("|").split("|")]
            parts.append("<tr>" + "".join(f"<{tag}>{_inline(c)}</{tag}>" for c in cells) + "</tr>")
        parts.append("</table>")
    parts += [f"<p>{_inline(t)}</p>" for t in after]
    return parts


def html_report(title: str, tables_md: str, figures: dict[str, Figure], footer: str = "", description: str = "") -> str:
    """A self-contained HTML page: the Markdown tables as HTML tables, figures inline (base64) with alt text."""
    parts = [f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             "<style>body{font-family:sans-serif;max-width:1200px;margin:auto;padding:0 8px}"
             "table{border-collapse:collapse;font-size:12px;display:block;overflow-x:auto}"
             "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}td:first-child{text-align:left}"
             "code{background:#f3f3f3;padding:0 2px}</style></head><body>",
             f"<h1>{html.escape(title)}</h1>"]
    if description:
        parts.append(f"<p>{_inline(description)}</p>")
    for block in tables_md.split("### ")[1:]:
        parts += _html_block(block)
    for name, figure in figures.items():
        parts.append(f"<h2>{html.escape(name)}</h2><img style='max-width:100%' alt='{html.escape(figure.alt, quote=True)}' "
                     f"src='data:image/png;base64,{base64.b64encode(figure.png).decode()}'>")
    if footer:
        parts.append(f"<p><small>{_inline(footer)}</small></p>")
    parts.append("</body></html>")
    return "\n".join(parts)
