"""Write docs/reference.md, the API reference, from the code: every public name's signature and docstring; and
docs/api.md, the docs site's page of the same names, which mkdocstrings fills from the docstrings when the site is
built (``mkdocs.yml``).

Run ``python docs/reference.py`` (``make docs``) after changing a public signature or docstring;
``tests/test_docs.py`` fails while the pages and the code disagree, so the reference cannot drift.
"""

import inspect
import sys
from pathlib import Path

import brdffit

PAGE = Path(__file__).with_name("reference.md")
SITE_PAGE = Path(__file__).with_name("api.md")
SITE_HEADER = """# API reference

Every name `import brdffit` offers, from its docstring (the same as [reference.md](reference.md), which reads on its
own without the site).
"""
HEADER = """# API reference

Generated from the code by `docs/reference.py` (`make docs`): every name `import brdffit` offers, with its signature
and docstring. [python.md](python.md) is the guide to them.
"""


def entry(name: str) -> str:
    """One public name's section: its signature and its docstring (a class's with its fields and methods)."""
    value = getattr(brdffit, name)
    if inspect.ismodule(value):
        names = [member for member in getattr(value, "__all__", dir(value)) if not member.startswith("_")]
        return f"## `brdffit.{name}`\n\n{inspect.getdoc(value) or ''}\n\nMembers: {', '.join(f'`{n}`' for n in names)}."
    if inspect.isclass(value) or inspect.isfunction(value):
        try:
            signature = str(inspect.signature(value))
        except (TypeError, ValueError):
            signature = "(…)"
        kind = "class" if inspect.isclass(value) else "def"
        text = f"## `brdffit.{name}`\n\n```python\n{kind} {name}{signature}\n```\n\n{inspect.getdoc(value) or ''}"
        if inspect.isclass(value):
            for member, attribute in vars(value).items():
                if member.startswith("_") or not callable(getattr(attribute, "__func__", attribute)):
                    continue
                function = getattr(attribute, "__func__", attribute)
                doc = inspect.getdoc(function)
                if doc and inspect.isfunction(function):
                    text += f"\n\n### `{name}.{member}{inspect.signature(function)}`\n\n{doc}"
        return text
    shown = ", ".join(map(str, value)) if isinstance(value, dict) else repr(value)
    return f"## `brdffit.{name}`\n\n`{type(value).__name__}`: {shown}"


def public_names() -> list[str]:
    return sorted((name for name in brdffit.__all__ if name != "__version__"), key=str.lower)


def reference() -> str:
    return HEADER + "\n" + "\n\n".join(entry(name) for name in public_names()) + "\n"


def site_page() -> str:
    """The site's page: a mkdocstrings block for each public name (a module's members are listed under it)."""
    return SITE_HEADER + "\n" + "\n\n".join(f"::: brdffit.{name}" for name in public_names()) + "\n"


if __name__ == "__main__":
    pages = {PAGE: reference(), SITE_PAGE: site_page()}
    if "--check" in sys.argv:
        sys.exit(0 if all(page.read_text() == text for page, text in pages.items()) else 1)
    for page, text in pages.items():
        page.write_text(text)
