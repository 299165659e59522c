#!/usr/bin/env python3
"""Run the brdffit command line from a checkout: ``python cli.py …`` does what ``brdffit …`` does."""

from brdffit.cli import run

if __name__ == "__main__":
    run()
