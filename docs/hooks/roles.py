"""MkDocs hook: the Sphinx roles in our numpy docstrings (``:func:`name```, ``:class:`~a.B```),
which mkdocstrings leaves as text, rendered as code, linked where the page documents the name.

A role renders as ``:func:<code>name</code>``; it becomes ``<code>name</code>``, shortened to its
last part when written with ``~``, and a link to the object's anchor when the page has one (the
API reference anchors every object it documents by its dotted path).
"""

from __future__ import annotations

import re

ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj|const):<code>(~?)([^<]+)</code>")
ANCHOR = re.compile(r'id="([A-Za-z_][\w.]*)"')


def on_page_content(html, page, config, files):
    anchors = set(ANCHOR.findall(html))

    def render(match):
        short, name = match.group(1) == "~", match.group(2).strip()
        shown = name.rsplit(".", 1)[-1] if short else name
        last = name.rsplit(".", 1)[-1]
        candidates = (name, f"toonmotion.api.{last}", f"toonmotion.{last}")
        target = next((a for a in candidates if a in anchors), None)
        code = f"<code>{shown}</code>"
        return f'<a href="#{target}">{code}</a>' if target else code

    return ROLE.sub(render, html)
