# The two commands of the README: `make demo` and `make test`. Everything they need is
# installed here, into .venv (Python packages) and by scripts/ (Debian packages).
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin

.PHONY: demo test lint typecheck pytest bench bytecode clean

demo: $(VENV)/.stamp-run bytecode
	bash scripts/install-document-tools.sh  # the Documentation screen renders PDF
	bash scripts/install-c-compiler.sh $(BIN)/python  # the runtime runs program bodies as C
	bash scripts/install-codemirror.sh  # the browser's code editor
	$(BIN)/padt demo

test: $(VENV)/.stamp-dev
	bash scripts/install-chromium.sh
	bash scripts/install-mbpoll.sh
	bash scripts/install-document-tools.sh
	bash scripts/install-mcap-reader.sh
	bash scripts/install-opcua-client.sh
	bash scripts/install-codemirror.sh
	bash scripts/install-c-compiler.sh $(BIN)/python
	bash scripts/install-junit-schema.sh $(BIN)/python
	$(MAKE) lint typecheck pytest

lint: $(VENV)/.stamp-dev
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/lint-imports --no-cache

typecheck: $(VENV)/.stamp-dev
	$(BIN)/mypy

pytest: $(VENV)/.stamp-dev bytecode
	$(BIN)/pytest -n 2 --dist loadfile -m "not slow" --durations=15 --tb=short

bench: $(VENV)/.stamp-run bytecode
	bash scripts/install-codemirror.sh  # the editor's bench types into it
	$(BIN)/python -m tests.bench

# Our sources compiled to bytecode once. Where the environment says PYTHONDONTWRITEBYTECODE
# (as on our build machines) every process would otherwise compile some 300 modules again
# as it starts: every runtime, compile worker and padt command the tests run, 0.7 s each.
bytecode: $(VENV)/.stamp-run
	$(BIN)/python -m compileall -q padt backend runtime frontend tests

$(VENV)/.stamp-run: pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q -e .
	touch $@

$(VENV)/.stamp-dev: pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q -e '.[dev]'
	touch $@ $(VENV)/.stamp-run

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache
	find padt backend runtime frontend tests -name __pycache__ -prune -exec rm -rf {} +
