"""``python -m brdffit …`` does what ``brdffit …`` does (the installed command, ``brdffit.cli:run``)."""

from .cli import run

if __name__ == "__main__":
    run()
