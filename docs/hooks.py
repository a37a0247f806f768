"""MkDocs hook: a navigation that follows the pages that exist.

The site lists pages that other parts of the project are still writing
(tutorials, API pages of packages in progress).  Rather than fail the strict
build on a missing page, its entry is dropped and named in the build log; and
a page written but not yet in ``mkdocs.yml`` is listed under "More", so every
page can be reached.
"""

from __future__ import annotations

import logging
from pathlib import Path

log = logging.getLogger("mkdocs.hooks.nav")


def _prune(items, docs: Path, dropped: list):
    out = []
    for item in items:
        if isinstance(item, dict):
            (title, value), = item.items()
            if isinstance(value, list):
                value = _prune(value, docs, dropped)
                if value:
                    out.append({title: value})
                continue
            if isinstance(value, str) and value.endswith(".md") and not (docs / value).is_file():
                dropped.append(value)
                continue
            out.append(item)
        elif isinstance(item, str) and item.endswith(".md") and not (docs / item).is_file():
            dropped.append(item)
        else:
            out.append(item)
    return out


def _listed(items) -> set[str]:
    out: set[str] = set()
    for item in items:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        if isinstance(value, list):
            out |= _listed(value)
        elif isinstance(value, str):
            out.add(value)
    return out


def on_config(config, **kwargs):
    """Drop nav entries for missing pages; list pages missing from the nav under "More"."""
    dropped: list[str] = []
    nav = config.get("nav")
    if nav:
        docs = Path(config["docs_dir"])
        nav = _prune(nav, docs, dropped)
        listed = _listed(nav)
        extra = sorted(p.relative_to(docs).as_posix() for p in docs.rglob("*.md"))
        extra = [p for p in extra if p not in listed]
        if extra:
            nav.append({"More": extra})
            log.info("pages not in mkdocs.yml, listed under More: %s", ", ".join(extra))
        config["nav"] = nav
    if dropped:
        log.info("pages not written yet, left out of the navigation: %s", ", ".join(dropped))
    return config
