"""Where the tests find the project's files, and the reference data that ships beside the project (not in it)."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "ward-pickled-oak.csv"
EXAMPLE_PARAMS = ROOT / "examples" / "ward-pickled-oak.params.json"
#: The real retro-reflective tape that ships in examples/ (ALTA format, values cosine-weighted by the view).
TAPE = ROOT / "examples" / "retro-gray-tape.dat"
#: ../shared/data: absent on a user's machine, where the tests that need it skip with a reason.
SHARED_DATA = ROOT.parent / "shared" / "data"
NGAN_FOLDER = SHARED_DATA / "ngan2005"
