PY := .venv/bin/python
STAMP := .venv/.installed

.PHONY: sweep example test test-slurm bench clean distclean docs

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv .venv
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $(STAMP)

# Its outputs are ignored by git. --resume continues a run that was interrupted, --force replaces the last one's file.
sweep: $(STAMP)
	mkdir -p results
	.venv/bin/dlasweep sweep dlasweep/sweep/specs/quick.toml -o results/quick.nc --resume --force
	.venv/bin/dlasweep report results/quick.nc -o results/quick

# The committed example of the quick report: refresh it when the report changes.
example: sweep
	.venv/bin/dlasweep report results/quick.nc -o results/examples/quick

# On every core, a test file to a worker (the files' module fixtures are shared by their tests), in the
# order tests/conftest.py gives them (the longest first).
test: $(STAMP)
	$(PY) -m pytest -n auto --dist loadfile --no-loadscope-reorder

# The launcher on a one-node SLURM started for the test (as root; apt installs slurm-wlm and munge if missing).
test-slurm: $(STAMP)
	$(PY) -m pytest tests/test_slurm.py

bench: $(STAMP)
	.venv/bin/dlasweep bench -o results/bench

# The sweep's outputs and the parts of an interrupted one (the committed results stay).
clean:
	rm -rf results/quick.nc results/quick results/*.parts

# clean, and the venv.
distclean: clean
	rm -rf .venv

# The documentation site, into docs/_build/html (its tables made from the package's, the lesson run at a small n).
docs: $(STAMP)
	$(PY) -m sphinx -b html docs docs/_build/html
