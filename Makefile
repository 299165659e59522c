# Two commands set everything up on a machine with python3 and make:
#   make demo   builds .venv and fits the shipped example, printing the fitted table
#   make test   builds .venv and runs the tests but the slow ones (CI runs it, then make test-slow)
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow test-install test-lowest test-heavy notebooks bench bench-pca bench-renderers bench-exports bench-phases bench-kernels bench-reading bench-threads bench-svbrdf lint format docs examples clean

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

# The tests in two parts: `make test` all but the slow ones (~2,200 tests, 15 minutes on 2 cores), `make test-slow` those
# marked slow (~300: cases of ten seconds or more, the catalogue's models beyond one of each kind; 22 minutes). CI runs
# both.
test: $(STAMP) $(VALIDATOR)
	$(BIN)/python -m pytest -n 2 -q

test-slow: $(STAMP) $(VALIDATOR)
	$(BIN)/python -m pytest -n 2 -q -m 'slow and not heavy'

# The lowest versions pyproject.toml allows (issue 30: what `pip install brdffit` may give a user): a second venv
# resolved by uv with --resolution lowest-direct (every direct dependency at its lower limit, the package installed
# from the clone as a wheel), `python -m brdffit` and a fit of the example from another folder, the wheel and the sdist
# built and checked for LICENSE, py.typed and (the sdist) the tests (tests/dist_contents.py), and the tests of
# LOWEST_TESTS: the models, the exports and Mitsuba, the uncertainty and emcee, the solver, the stored programs and
# executables (JAX's private LAPACK set-up) and stored pairs, pandas and colour-science, Dask, the command line's
# streams and extras (~10 minutes on 2 cores). Needs the package index; CI runs it after `make test`.
LOWEST := .venv-lowest
LOWEST_TESTS := tests/physics tests/export tests/uncertainty tests/fitting/test_fit.py tests/fitting/test_solver.py \
	tests/data/test_formats.py tests/data/test_spectral.py tests/cli/test_streams.py tests/cli/test_extras.py \
	tests/test_cluster.py tests/test_programs.py tests/test_executables.py tests/data/test_stored_pairs.py \
	tests/test_jit.py tests/test_float64.py tests/test_startup.py
test-lowest: $(STAMP) $(VALIDATOR)
	$(BIN)/python -m pip install --quiet 'uv>=0.5'
	rm -rf $(LOWEST)
	$(BIN)/uv venv --quiet --python $(BIN)/python $(LOWEST)
	$(BIN)/uv pip install --quiet --python $(LOWEST)/bin/python --resolution lowest-direct '.[test]'
	$(LOWEST)/bin/python -c "import jax, numpy, optimistix, equinox; print('lowest:', 'jax', jax.__version__, \
		'numpy', numpy.__version__, 'optimistix', optimistix.__version__, 'equinox', equinox.__version__)"
	cd $(LOWEST) && bin/python -m brdffit --version
	cd $(LOWEST) && BRDFFIT_CACHE_DIR=cache bin/brdffit fit ../examples/ward-pickled-oak.csv --model ward -q -o ward.json
	$(BIN)/uv build --quiet --sdist --wheel --out-dir $(LOWEST)/dist
	$(BIN)/python tests/dist_contents.py $(LOWEST)/dist
	$(LOWEST)/bin/python -m pytest -n 2 -q -m 'not heavy' $(LOWEST_TESTS)

# `pip install <clone>` as a user does it (issue 30): a third venv, the package installed from the clone as a wheel (not
# editable) with the pinned versions, then `python -m brdffit --version` and a fit of the example from another folder,
# which must not see the clone's sources (~1 minute; needs the package index or uv's cache). CI runs it.
INSTALLED := .venv-installed
test-install: $(STAMP)
	$(BIN)/python -m pip install --quiet 'uv>=0.5'
	rm -rf $(INSTALLED)
	$(BIN)/uv venv --quiet --python $(BIN)/python $(INSTALLED)
	$(BIN)/uv pip install --quiet --python $(INSTALLED)/bin/python -c constraints.txt .
	cd $(INSTALLED) && bin/python -c "import brdffit, sys; assert 'site-packages' in brdffit.__file__, brdffit.__file__"
	cd $(INSTALLED) && bin/python -m brdffit --version
	cd $(INSTALLED) && BRDFFIT_CACHE_DIR=cache bin/brdffit fit ../examples/ward-pickled-oak.csv --model ward -o ward.json
	cd $(INSTALLED) && bin/python -c "import json; print('installed fit, cost', json.load(open('ward.json'))['fit']['cost'])"

test-heavy: $(STAMP) $(VALIDATOR)
	$(BIN)/python -m pytest -n 2 -q -m heavy

# The notebooks run in Jupyter's kernel, their outputs kept in the files (issue 30; ~3 minutes): run it after a change
# that changes what they show. tests/test_notebooks.py checks that every code cell kept its output.
notebooks: $(STAMP)
	$(BIN)/python -m pip install --quiet 'nbclient>=0.10' ipykernel
	$(BIN)/python notebooks/execute.py

# The benchmarks of issues 3 and 4 (not tests): ~30 minutes, prints a table, writes benchmarks/results/latest.{json,md}.
bench: $(STAMP)
	$(BIN)/python benchmarks/run.py

# The data-driven model's benchmark (issue 15): a library of 100 MERL tables (~3.5 GB, ~3 minutes, written once),
# the basis build's time and memory, and held-out materials fitted from 20 pairs; writes benchmarks/results/pca.{json,md}.
LIBRARY ?= $(HOME)/.cache/brdffit-library
bench-pca: $(STAMP)
	$(BIN)/python -m brdffit.data_synth.library $(LIBRARY) --analytic 60 --mitsuba 40
	$(BIN)/python benchmarks/pca.py $(LIBRARY)

# Into the renderer (issue 28): materials made by Mitsuba 3's BSDFs, compared, fitted and exported, each export
# evaluated by Mitsuba at the data's directions (~10 minutes); writes benchmarks/results/renderers.{json,md}.
bench-renderers: $(STAMP)
	$(BIN)/python benchmarks/renderers.py

# Exports and renders timed in fresh processes, cold and warm (issue 28; ~10 minutes); writes
# benchmarks/results/exports.{json,md}. BASELINE=CHECKOUT times another checkout in the same rounds.
bench-exports: $(STAMP)
	$(BIN)/python benchmarks/exports.py $(if $(BASELINE),--baseline $(BASELINE))

# Where a single fit's time goes (issue 32): the example's brdffit fit and a MERL-size Cook-Torrance fit, cold and
# warm, phase by phase (~5 minutes); writes benchmarks/results/phases.{json,md}, which docs/scale.md quotes.
bench-phases: $(STAMP)
	$(BIN)/python benchmarks/phases.py

# Where a normal-equation pass's time goes (issue 32's step goal): its kernels, profiled, at MERL size, for
# Cook-Torrance and Ward (~2 minutes); writes benchmarks/results/kernels.{json,md}, which docs/scale.md quotes.
bench-kernels: $(STAMP)
	$(BIN)/python benchmarks/kernels.py

# Spatially varying materials (issue 31): per-texel cost against a scipy loop, where it goes, compilation, and a
# 256 × 256 capture end to end (~5 minutes); writes benchmarks/results/svbrdf.{json,md}.
bench-svbrdf: $(STAMP)
	$(BIN)/python benchmarks/svbrdf.py

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
	$(BIN)/brdffit synth capture examples/ward-capture --texels 32,32 --images 24 --noise 0.01 --seed 0

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache *.egg-info
