# Two commands set everything up on a machine with python3 and make:
#   make demo   builds .venv and fits the shipped example, printing the fitted table
#   make test   builds .venv and runs the tests (what CI runs)
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-heavy bench bench-pca bench-renderers bench-exports bench-reading bench-threads lint format docs examples clean

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c constraints.txt -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(BIN)/brdffit fit examples/ward-pickled-oak.csv --model ward -o out/ward-pickled-oak.json

# The Khronos glTF validator (npm gltf-validator), which the glTF export's tests run; without npm they skip.
VALIDATOR := $(VENV)/node/node_modules/gltf-validator/package.json
$(VALIDATOR): $(STAMP)
	@if command -v npm >/dev/null; then \
		npm install --silent --no-audit --no-fund --prefix $(VENV)/node gltf-validator@2.0.0-dev.3.10; \
	else echo "npm not found: the tests that run the Khronos glTF validator will skip"; fi

test: $(STAMP) $(VALIDATOR)
	$(BIN)/python -m pytest -n 2 -q

test-heavy: $(STAMP) $(VALIDATOR)
	$(BIN)/python -m pytest -n 2 -q -m heavy

# The benchmarks of issues 3 and 4 (not tests): ~30 minutes, prints a table, writes benchmarks/results/latest.{json,md}.
bench: $(STAMP)
	$(BIN)/python benchmarks/run.py

# The data-driven model's benchmark (issue 15): a library of 100 MERL tables (~3.5 GB, ~3 minutes, written once),
# the basis build's time and memory, and held-out materials fitted from 20 pairs; writes benchmarks/results/pca.{json,md}.
LIBRARY ?= $(HOME)/.cache/brdffit-library
bench-pca: $(STAMP)
	$(BIN)/python -m data_synth.library $(LIBRARY) --analytic 60 --mitsuba 40
	$(BIN)/python benchmarks/pca.py $(LIBRARY)

# Into the renderer (issue 28): materials made by Mitsuba 3's BSDFs, compared, fitted and exported, each export
# evaluated by Mitsuba at the data's directions (~10 minutes); writes benchmarks/results/renderers.{json,md}.
bench-renderers: $(STAMP)
	$(BIN)/python benchmarks/renderers.py

# Exports and renders timed in fresh processes, cold and warm (issue 28; ~10 minutes); writes
# benchmarks/results/exports.{json,md}. BASELINE=CHECKOUT times another checkout in the same rounds.
bench-exports: $(STAMP)
	$(BIN)/python benchmarks/exports.py $(if $(BASELINE),--baseline $(BASELINE))

# Reading a samples file (issue 29): peak memory and time per row of load_samples on CSVs of 10⁵ and 10⁶ rows
# (~1 minute); writes benchmarks/results/reading.{json,md}.
bench-reading: $(STAMP)
	$(BIN)/python benchmarks/reading.py

# Issue 29's race: 300 files fitted with --threads 16, 10 runs, counting crashes (~5 minutes); writes
# benchmarks/results/threads.{json,md}.
bench-threads: $(STAMP)
	$(BIN)/python benchmarks/threads.py

# mypy: the package's types (pyproject.toml's [tool.mypy]).
lint: $(STAMP)
	$(BIN)/ruff format --check .
	$(BIN)/ruff check .
	$(BIN)/python -m mypy brdffit

format: $(STAMP)
	$(BIN)/ruff format .
	$(BIN)/ruff check --fix .

# Regenerates docs/reference.md, the API reference, from the code (a test fails while it is out of date).
docs: $(STAMP)
	$(BIN)/python docs/reference.py
	$(BIN)/mkdocs build --strict

# Regenerates the shipped example from its parameters (Ngan et al. 2005's Ward fit of pickled-oak-260).
examples: $(STAMP)
	$(BIN)/brdffit synth --model ward --params examples/ward-pickled-oak.params.json \
		--geometry hemisphere --noise 0.01 --seed 1 -o examples/ward-pickled-oak.csv

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache *.egg-info
