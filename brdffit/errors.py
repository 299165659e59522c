"""The one exception users see for bad input.

Every message is a single line that names the file (or option), the row and
column where there is one, what was wrong and what is allowed; the command line
prints it after ``brdffit: error:`` and exits with status 2.
"""


class BrdfInputError(ValueError):
    """Bad input: a file, an option or a parameter value that brdffit cannot accept."""
