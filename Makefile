PY := .venv/bin/python
STAMP := .venv/.installed

.PHONY: sweep test test-slurm bench clean

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv .venv
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $(STAMP)

sweep: $(STAMP)
	mkdir -p results
	.venv/bin/dlasweep sweep workflows/quick.toml -o results/quick.nc
	.venv/bin/dlasweep report results/quick.nc -o results/quick

test: $(STAMP)
	$(PY) -m pytest

# The launcher on a one-node SLURM started for the test (as root; apt installs slurm-wlm and munge if missing).
test-slurm: $(STAMP)
	$(PY) -m pytest tests/test_slurm.py

bench: $(STAMP)
	.venv/bin/dlasweep bench -o results/bench

clean:
	rm -rf .venv results/*.parts
