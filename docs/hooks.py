"""The docs site's hooks (``mkdocs.yml``). Pages link to files outside ``docs/`` (the README, the benchmarks'
results, the examples), as they must for the repository to read well on its own. The site holds each such file under
``repository/`` (a Markdown file as a page, anything else as it is), follows their links in turn, and points every
relative link of every page at where its target lies in the site, so that ``mkdocs build --strict`` finds each one.
And the docstrings' Sphinx roles (``:class:`~brdffit.Samples```), which mkdocstrings leaves as text, show as the code
they name.
"""

import posixpath
import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: A Markdown link or image target that is a relative path (not a URL, not an anchor alone).
LINK = re.compile(r"(\]\()(?![a-z]+:|#|/)([^)\s#]+)")


def _site_path(real: Path) -> str:
    """Where a file of the repository lies in the site: ``docs/``'s as they are, the rest under ``repository/``."""
    return real.relative_to(DOCS).as_posix() if real.is_relative_to(DOCS) else f"repository/{real.relative_to(ROOT)}"


def _real(site_path: str) -> Path:
    return ROOT / site_path.removeprefix("repository/") if site_path.startswith("repository/") else DOCS / site_path


def _targets(real: Path) -> list[Path]:
    """The files a Markdown file's relative links name, that exist."""
    found = []
    for _, target in LINK.findall(real.read_text(encoding="utf-8")):
        path = (real.parent / target).resolve()
        if path.is_file() and path.is_relative_to(ROOT):
            found.append(path)
    return found


def on_files(files, config):
    """Add every file outside ``docs/`` that the pages link to (and those linked from them), under ``repository/``."""
    waiting = [DOCS / file.src_uri for file in files if file.src_uri.endswith(".md")]
    seen = set(waiting)
    while waiting:
        for target in _targets(waiting.pop()):
            if target in seen or target.is_relative_to(DOCS):
                continue
            seen.add(target)
            files.append(File.generated(config, _site_path(target), abs_src_path=str(target)))
            if target.suffix == ".md":
                waiting.append(target)
    return files


def on_page_markdown(markdown, page, config, files):
    """Each relative link of the page pointed at where its target lies in the site."""
    here = _real(page.file.src_uri)

    def pointed(match):
        target = (here.parent / match.group(2)).resolve()
        if not (target.exists() and target.is_relative_to(ROOT)):
            return match.group(0)  # left for mkdocs to report
        relative = posixpath.relpath(_site_path(target), posixpath.dirname(page.file.src_uri) or ".")
        return match.group(1) + relative

    return LINK.sub(pointed, markdown)


#: A Sphinx role as the docstrings write it (``:class:`~brdffit.Samples```), once rendered: the role's name before
#: the code, and a ``~`` (Sphinx's "last part only") inside it.
ROLE = re.compile(r":(?:class|func|meth|data|attr|mod|exc|obj):<code>~?(?:[\w.]+\.)?([^<]*)</code>")


def on_page_content(html, page, config, files):
    """The docstrings' Sphinx roles shown as the code they name (``Samples``, not ``:class:~brdffit.Samples``):
    mkdocstrings renders the docstrings' Markdown, where a role is plain text."""
    return ROLE.sub(lambda match: f"<code>{match.group(1)}</code>", html)
