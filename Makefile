# fdi-book: the two entry points are `make book` and `make test`.
SHELL := /bin/bash
# Each creates/updates the virtual environment .venv from requirements.lock by itself.
PYTHON ?= $(shell command -v python3.11 2>/dev/null || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# All matrices here are small: one BLAS thread per process avoids oversubscription (see
# fdi_lib/threads.py); Monte Carlo parallelism is over processes.
export OPENBLAS_NUM_THREADS := 1
export OMP_NUM_THREADS := 1
export MKL_NUM_THREADS := 1

.PHONY: book book-execute book-pages book-fast test venv lock clean benchmarks student student-pdf notebooks browser-test browser-pages browser-notebooks check-book grade pdf install-check lint format system-deps

venv: $(STAMP)

$(STAMP): requirements.lock pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	$(BIN)/python -m pip install --quiet -r requirements.lock
	$(BIN)/python -m pip install --quiet --no-deps -e .
	$(BIN)/python -m ipykernel install --prefix $(VENV) --name python3 >/dev/null
	touch $(STAMP)

## Headless Chromium for the browser test and the page weights of `make book`: Debian's package.
CHROMIUM := /usr/bin/chromium
$(CHROMIUM):
	apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium
# Node.js (Debian's package, installed if absent) runs the book's MathJax to check that every
# notebook's maths typesets (tools/notebook_markdown.py check, tests/test_notebook_markdown.py).
NODE := /usr/bin/node
$(NODE):
	apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq nodejs

## Build the whole book, every notebook executed; fails on any cell error or Sphinx warning.
## The build log drops two lines the kernels print that are not problems of the book: ipykernel's
## notice that a kernel talks to the build over local TCP without encryption, and the
## "KeyboardInterrupt caught in kernel" that jupyter_client's interrupt-before-shutdown causes
## when a kernel is still finishing a message. Reproductions run by the chapters are cached for
## this build only, for the claims ledger. The chapters are executed first, side by side on the
## machine's cores (tools/execute_book.py: every chapter afresh, into a jupyter-cache emptied
## first; a cell error stops there), and Jupyter Book builds the pages from that cache (execution
## mode cache in _build/_config_book.yml, written by the script). Then tools/build_report.py prints
## the execution time of every chapter and the wall time of the build, measures what each page
## loads (headless Chromium, installed if absent as for the browser test) and writes both into the
## built status page, which is executed before any page is written and cannot measure them itself.
## BOOK_JOBS chapters at a time (default: the cores). The two halves are targets of their own,
## `book-execute` (the chapters, into the jupyter-cache and the results cache) and `book-pages`
## (Jupyter Book and the report), so that CI can start the student edition, which reuses the
## executed chapters, beside the pages; `make book` runs them one after the other.
KERNEL_NOISE := sed -u -e '/Kernel is running over TCP without encryption/d' \
                       -e '/KeyboardInterrupt caught in kernel/d'
book: $(STAMP) $(CHROMIUM)
	@$(MAKE) --no-print-directory book-execute
	@$(MAKE) --no-print-directory book-pages
	@echo "Book built: $(abspath _build/html/index.html)"

book-execute: export FDI_RESULTS_CACHE := $(CURDIR)/_build/results-cache
book-execute: $(STAMP)
	rm -rf _build/html _build/.doctrees _build/results-cache
	mkdir -p _build
	date +%s > _build/.book-started
	set -o pipefail; $(BIN)/python tools/execute_book.py --cache _build/.jupyter_cache-book \
	  --config-out _build/_config_book.yml $(if $(BOOK_JOBS),--jobs $(BOOK_JOBS)) 2>&1 \
	  | $(KERNEL_NOISE) | tee _build.log

book-pages: export FDI_RESULTS_CACHE := $(CURDIR)/_build/results-cache
book-pages: $(STAMP) $(CHROMIUM)
	@test -f _build/_config_book.yml && test -f _build/.book-started || { echo "No executed chapters: run make book-execute first"; exit 2; }
	set -o pipefail; $(BIN)/jupyter-book build . --config _build/_config_book.yml \
	  --warningiserror --nitpick --keep-going --builder html 2>&1 | $(KERNEL_NOISE) | tee -a _build.log
	$(BIN)/python tools/build_report.py --html _build/html --log _build.log --started $$(cat _build/.book-started)

## Authoring mode: re-execute only the chapters whose text changed since the last book-fast
## (jupyter-cache), with a cache keyed by the library's source (a change in fdi_lib re-executes
## everything). `make book` and CI still force every chapter.
LIB_HASH = $(shell find fdi_lib -name '*.py' | LC_ALL=C sort | xargs cat | sha1sum | cut -c1-12)
FAST_CACHE = $(CURDIR)/_build/.jupyter_cache-$(LIB_HASH)
book-fast: $(STAMP)
	mkdir -p _build
	find _build -maxdepth 1 -name '.jupyter_cache-*' ! -name '.jupyter_cache-$(LIB_HASH)' -exec rm -rf {} +  # stale caches
	sed -e 's|^\(  execute_notebooks:\) force.*|\1 cache|' -e 's|^\(  timeout:.*\)|\1\n  cache: $(FAST_CACHE)|' \
	    -e 's|^\(    fdi_book:\) _ext|\1 $(CURDIR)/_ext|' _config.yml > _build/_config_fast.yml
	grep -q 'execute_notebooks: cache' _build/_config_fast.yml
	set -o pipefail; $(BIN)/jupyter-book build . --config _build/_config_fast.yml --builder html --keep-going 2>&1 | tee _build/book-fast.log
	@echo "Book built (cached execution): $(abspath _build/html/index.html)"

## Student edition: the same book without the exercise solutions (_build/student/html) and one
## notebook per chapter with the starter cells (_build/student/notebooks); fails if either still
## contains solution text (tools/student_edition.py verify). Then the student package, a wheel of
## fdi_lib without reference answers or reference code (_build/student/dist/fdi_lib-*.whl,
## tools/student_package.py; digests of the book's data only: graded answers stay out of it).
student: $(STAMP) $(NODE)
	mkdir -p _build/student
	set -o pipefail; $(BIN)/python tools/student_edition.py build --warningiserror --nitpick --keep-going 2>&1 | tee _build/student/build.log
	$(BIN)/python tools/student_package.py --out _build/student
	@echo "Student book built: $(abspath _build/student/html/index.html)"
	@echo "Student package: $$(ls _build/student/dist/fdi_lib-*.whl) (pip install it; no repository needed)"
	$(MAKE) student-pdf

## Grade a class: SUBMISSIONS holds one folder per student id with the submitted notebooks; OUT
## gets the gradebook (one row per student, written as each finishes; a re-run resumes), beside it
## OUT's .log, .feedback/ (one file per student), .canvas.csv, .similarity.csv. The notebooks run
## in isolated kernels against the student package, on each student's own data and on hidden data
## (tools/grader.py); GRADE_JOBS kernels at once (default 2), GRADE_ARGS for the limits
## (e.g. --cell-timeout 60 --student-timeout 600 --memory-mb 3072). Without SUBMISSIONS, a
## synthetic class with hostile submissions (tools/make_synthetic_class.py) is written to
## _build/synthetic-class and graded into _build/synthetic-class.csv.
GRADE_JOBS ?= 2
grade: $(STAMP)
	@if [ -z "$(SUBMISSIONS)" ]; then rm -rf _build/synthetic-class _build/synthetic-class.*; \
	  $(BIN)/python tools/make_synthetic_class.py _build/synthetic-class \
	    $(if $(CHAPTERS),--chapters $(CHAPTERS)); fi
	$(BIN)/python tools/grader.py "$(or $(SUBMISSIONS),_build/synthetic-class)" \
	  "$(or $(OUT),_build/synthetic-class.csv)" --jobs $(GRADE_JOBS) $(GRADE_ARGS)

## PDF edition: _build/pdf/fdi-book.pdf, by xelatex from Debian's TeX Live (the packages below,
## installed if absent, as browser-test installs chromium; no network otherwise). It reuses the
## notebooks executed by the last `make book` (_build/jupyter_execute) through a jupyter-cache,
## executing only the chapters that changed since (all of them without an HTML build), checks
## the PDF (tools/check_pdf.py) and, after `make book`, puts it beside the pages, whose header
## menu then links it (tools/pdf_edition.py).
TEX_PACKAGES := texlive-xetex texlive-latex-extra texlive-fonts-recommended fonts-freefont-otf lmodern \
                fonts-dejavu-core fonts-dejavu-extra latexmk poppler-utils
TEX_INSTALL = dpkg -s $(TEX_PACKAGES) >/dev/null 2>&1 || { apt-get update -qq && \
              DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $(TEX_PACKAGES); }
pdf: $(STAMP)
	$(TEX_INSTALL)
	mkdir -p _build
	set -o pipefail; $(BIN)/python tools/pdf_edition.py build --out _build/pdf --executed _build/jupyter_execute \
	  --html _build/html 2>&1 | sed -u -e '/Kernel is running over TCP without encryption/d' | tee _build/pdf.log

## The student edition's PDF (_build/student/pdf/fdi-book.pdf), from the sources and executed
## notebooks of `make student`.
student-pdf: $(STAMP)
	$(TEX_INSTALL)
	set -o pipefail; $(BIN)/python tools/pdf_edition.py build --src _build/student/src --out _build/student/pdf \
	  --executed _build/student/build/_build/jupyter_execute --html _build/student/html 2>&1 \
	  | sed -u -e '/Kernel is running over TCP without encryption/d' | tee _build/student/pdf.log
	$(BIN)/python tools/student_edition.py verify

## Plain .ipynb copies of the chapters (outputs not executed) under _build/notebooks/, which the book
## ignores (a .ipynb beside a chapter is excluded too, see exclude_patterns in _config.yml), in
## Markdown that Jupyter renders: the book's macros defined, roles and directives resolved, glued
## values from the last book build (_build/jupyter_execute) or, without one, a placeholder naming
## the value (tools/notebook_markdown.py).
notebooks: $(STAMP) $(NODE)
	rm -rf _build/notebooks
	$(BIN)/python tools/notebook_markdown.py notebooks --out _build/notebooks
	$(BIN)/python tools/notebook_markdown.py check $$(find _build/notebooks -name '*.ipynb')

## Every page of the built book in headless Chromium (Debian's package, installed if absent),
## at 1280 px and as a phone (mobile emulation: 390x844, scale 2, touch), no network; screenshots
## of both in _build/screenshots/ (tests/browser/check_book.py); hover previews (check_previews.py);
## what each page loads against the page budget (page_weights.py).
## axe-core (the npm registry's package, this version) checks every page's accessibility in the
## browser test; it is installed under _build/axe for the test only, never into the built pages.
AXE_VERSION := 4.14.1
AXE_JS := _build/axe/node_modules/axe-core/axe.min.js
NPM := /usr/bin/npm
$(NPM):
	apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq npm
$(AXE_JS): | $(NODE) $(NPM)
	npm install --silent --no-save --no-package-lock --no-audit --no-fund --prefix _build/axe \
	  axe-core@$(AXE_VERSION)

## The Debian packages that the targets install when absent (Chromium, Node.js, npm, TeX
## Live), all at once: .ci/run installs them first, before it runs steps side by side (two apt-get
## at once wait on each other's lock, or fail).
system-deps: $(CHROMIUM) $(NODE) $(NPM)
	$(TEX_INSTALL)

## The live notebooks as the README opens them: `make notebooks`, then JupyterLab (headless, on
## 127.0.0.1) shows each in Chromium with no raw MyST role, directive or undefined macro
## (tests/browser/check_jupyterlab.py). `browser-test` runs both halves, `browser-pages` (the built
## pages) and `browser-notebooks` (JupyterLab), which CI runs in its two lanes.
browser-test: browser-pages browser-notebooks

browser-notebooks: $(STAMP) $(CHROMIUM) notebooks
	$(BIN)/python tests/browser/check_jupyterlab.py --notebooks _build/notebooks

browser-pages: $(STAMP) $(CHROMIUM) $(AXE_JS)
	@test -f _build/html/index.html || { echo "No built book: run make book first"; exit 2; }
	$(BIN)/python tests/browser/check_book.py --html _build/html --screenshots _build/screenshots \
	  --axe $(AXE_JS)
	$(BIN)/python tests/browser/check_explorables.py --html _build/html
	$(BIN)/python tests/browser/check_previews.py --html _build/html
	$(BIN)/python tests/browser/page_weights.py --html _build/html --report _build/build-report.json

## Post-build checks of what the built book claims (after `make book`, which leaves its results
## cache): every figure caption's verb ("reproduces" / "compare with") agrees with the claims ledger
## (tests/browser/check_captions.py), and every command printed by the catalogue, run afresh without
## the cache, gives the result the chapter showed (tools/check_catalogue.py; it recomputes every
## reproduction at the book's trial counts, about as long as the book's execution), and every
## .ipynb download renders in Jupyter (tools/notebook_markdown.py check: no raw role, macros defined).
check-book: $(STAMP) $(NODE)
	@test -f _build/html/index.html || { echo "No built book: run make book first"; exit 2; }
	$(BIN)/python tests/browser/check_captions.py --html _build/html --cache _build/results-cache
	$(BIN)/python tools/check_catalogue.py --html _build/html --cache _build/results-cache --jobs 2
	$(BIN)/python tools/notebook_markdown.py check $$(find _build/html/_sources -name '*.ipynb')

## Run the whole test suite, TEST_JOBS processes at a time (pytest-xdist; default: one per core,
## TEST_JOBS=0 runs it in this process). Each test's temporary files are its own (tmp_path). A test
## module runs on one process (--dist loadscope), so a module's fixture is computed once: split
## over two processes, the grader's synthetic class was graded twice (99 s each). The 15 slowest
## tests are listed at the end (where the suite's wall time goes on 2 cores).
TEST_JOBS ?= auto
test: $(STAMP) $(NODE)
	$(BIN)/python -m pytest -q -n $(TEST_JOBS) --dist loadscope --durations=15

## Performance targets (issues 10 and 16): each prints its figure, target and ratio; the figures are
## also collected in _build/benchmarks.json, which the book's status page shows when present.
## bench_notebooks.py runs every chapter with a widget in a fresh kernel up to its widget, as a
## student would: 6 fresh kernels, at most 3 min once each chapter meets its 30 s (4.5 min under
## load before the speed-ups of this session); `make benchmarks NOTEBOOKS=0` skips it.
NOTEBOOKS ?= 1
benchmarks: $(STAMP)
	mkdir -p _build; rm -f _build/benchmarks.json
	for f in benchmarks/bench_*.py; do \
	  if [ "$$f" = benchmarks/bench_notebooks.py ] && [ "$(NOTEBOOKS)" = 0 ]; then echo "== $$f skipped (NOTEBOOKS=0)"; continue; fi; \
	  echo "== $$f"; t0=$$(date +%s); \
	  FDI_BENCH_JSON=$(CURDIR)/_build/benchmarks.json $(BIN)/python $$f || exit 1; \
	  echo "== $$f: $$(( $$(date +%s) - t0 )) s"; \
	done

## Re-pin requirements.lock from the current environment (maintainers only).
lock:
	$(BIN)/python -m pip freeze --exclude-editable | grep -v '^fdi[-_]lib' > requirements.lock

clean:
	rm -rf _build _build.log

## The library alone (issue 34): its wheel installed into a new, clean virtual environment (deps
## held to requirements.lock), then `fdi-reproduce --list` and one reproduction's --json there
## (tools/check_install.py; _build/install-check/).
install-check: $(STAMP)
	$(BIN)/python tools/check_install.py --out _build/install-check

## Lint (ruff, configured in pyproject.toml at 100 columns; run by CI). `make format` rewrites the
## tree in the formatter's layout; `ruff format --check` joins this target in the commit that formats
## the whole tree once (issue 34), not before.
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: $(STAMP)
	$(BIN)/ruff format .
