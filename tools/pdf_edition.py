"""The PDF edition of the book (``make pdf``): ``_build/pdf/fdi-book.pdf``, by xelatex.

    python tools/pdf_edition.py build [--src .] [--out _build/pdf] [--executed DIR] [--html DIR]

``build``

1. fills a jupyter-cache (``OUT/.jupyter_cache-<hash of fdi_lib's sources>``, as ``make
   book-fast``) with the notebooks that the HTML build executed (``--executed``, its
   ``jupyter_execute`` folder: each chapter's executed notebook and its glued values, which
   myst-nb keeps apart in ``<chapter>.glue.json``), so that the LaTeX build takes their outputs
   instead of executing every chapter a second time. A notebook older than the newest source
   file of ``fdi_lib`` is not taken (it may show what an older library computed), and a chapter
   is taken from the cache only if its code cells are those of the sources (jupyter-cache
   compares a hash of them); any other chapter, or every chapter without an HTML build, is
   executed by the LaTeX build and cached for the next one. The HTML build leaves the
   explorables' small multiples for paper out (:func:`paper_figures` draws them here, from the
   specification in their place);
2. runs Jupyter Book's ``pdflatex`` builder with the book's ``_config.yml`` (its ``latex:``
   section: xelatex, the parts of ``_toc.yml``; execution mode ``cache`` on the cache above),
   strict as ``make book`` is (``--warningiserror --nitpick``), and xelatex in batch mode with
   ``-halt-on-error``: a LaTeX error fails the build;
3. copies the PDF to ``OUT/fdi-book.pdf``, checks it (``tools/check_pdf.py``) and, when
   ``--html`` holds a built book, puts it beside the pages, whose header menu then links it
   (``publish_pdf`` of ``_ext/fdi_book.py``);
4. typesets the same LaTeX source again on A4 paper (:func:`a4_edition`): ``OUT/fdi-book-a4.pdf``,
   beside the US letter one (Sphinx's default paper), and beside the pages too; checked as the
   letter one is (its narrower text block, its own page breaks).
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def library_files() -> list[Path]:
    """The source files of the ``fdi_lib`` that the chapters' kernels import."""
    import importlib.util

    spec = importlib.util.find_spec("fdi_lib")
    return sorted(Path(next(iter(spec.submodule_search_locations))).rglob("*.py"))


def library_hash() -> str:
    return hashlib.sha1(b"".join(p.read_bytes() for p in library_files())).hexdigest()[:12]


def prime_cache(executed: Path, cache_dir: Path, newer_than: float = 0.0) -> int:
    """Add every executed notebook under ``executed`` modified after ``newer_than`` (a time
    stamp) to the jupyter-cache at ``cache_dir``, its glued values put back as the display
    outputs myst-nb reads them from; returns how many. A notebook without any executed cell is
    left out: an HTML build in execution mode ``force`` (``make book``) writes the executed
    notebooks, one in mode ``cache`` (``make book-fast``) the notebooks as read.

    myst-nb writes ``<doc>.ipynb`` after taking out the outputs of ``glue(..., display=False)``
    (kept in ``<doc>.glue.json``, with their metadata): without them the LaTeX build would find
    no glued value. They go back into the first code cell (the order of glue outputs is not
    read; their keys are)."""
    import nbformat
    from jupyter_cache import get_cache
    from jupyter_cache.base import CacheBundleIn

    cache = get_cache(str(cache_dir))
    n = 0
    for path in sorted(executed.rglob("*.ipynb")):
        if path.stat().st_mtime <= newer_than:
            continue
        nb = nbformat.read(path, as_version=4)
        code = [c for c in nb.cells if c.cell_type == "code"]
        if not any(c.get("execution_count") for c in code):
            continue  # not executed: myst-nb's cache mode (book-fast) writes the unexecuted notebook
        glue_file = path.with_name(path.stem + ".glue.json")
        if code and glue_file.is_file():
            shown = {
                o.get("metadata", {}).get("scrapbook", {}).get("name")
                for c in code
                for o in c.get("outputs", [])
            }
            for key, output in json.loads(glue_file.read_text()).items():
                if key in shown:
                    continue
                output = copy.deepcopy(output)
                prefix = output.get("metadata", {}).get("scrapbook", {}).get("mime_prefix", "")
                output["data"] = {prefix + k: v for k, v in output["data"].items()}
                code[0].outputs.append(nbformat.from_dict(output))
        drawn = paper_figures(code)
        if drawn:
            print(f"pdf: {path.name}: {drawn} explorables' small multiples drawn", flush=True)
        # its run time in the HTML build, for the status page (_ext/fdi_book.py writes it)
        timing = path.with_name(path.stem + ".exec.json")
        data = (
            {"execution_seconds": json.loads(timing.read_text())["runtime"]}
            if timing.is_file()
            else {}
        )
        cache.cache_notebook_bundle(
            CacheBundleIn(nb, str(path), data=data), check_validity=False, overwrite=True
        )
        n += 1
    return n


def paper_figures(cells: list) -> int:
    """The small multiples of every explorable among the outputs of ``cells`` that carries their
    specification in their place (``tools/execute_book.py`` defers them: the HTML pages never
    show them), drawn by :func:`fdi_lib.explorables.paper_figure` as the ``image/png`` output
    that myst-nb's LaTeX builder takes, the same bytes as the kernel would have drawn; returns
    how many."""
    import base64

    from fdi_lib.explorables import PAPER_SPEC_MIME, paper_figure

    n = 0
    for cell in cells:
        for output in cell.get("outputs", []):
            data = output.get("data", {})
            if PAPER_SPEC_MIME in data and "image/png" not in data:
                png = paper_figure(data[PAPER_SPEC_MIME])
                data["image/png"] = base64.b64encode(png).decode("ascii")
                n += 1
    return n


def pdf_config(src: Path, cache_dir: Path, target: Path) -> Path:
    """The book's ``_config.yml`` with execution mode ``cache`` on ``cache_dir`` and the local
    extension's folder made absolute (the file is written outside the book), at ``target``."""
    import yaml

    config = yaml.safe_load((src / "_config.yml").read_text())
    config.setdefault("execute", {}).update(execute_notebooks="cache", cache=str(cache_dir))
    local = config.get("sphinx", {}).get("local_extensions") or {}
    for name, folder in local.items():
        local[name] = str((src / folder).resolve())
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(yaml.safe_dump(config, sort_keys=False, allow_unicode=True))
    return target


#: The part of ``_toc.yml`` that the printed book leaves out: the library reference (book/api/),
#: some 200 pages of signatures generated from the docstrings, is read online beside the code; the
#: PDF's map of the book names it without a link (``NO_PDF_CHAPTER`` of ``_ext/fdi_book.py``).
ONLINE_ONLY = "book/api/"


def pdf_toc(src: Path, target: Path) -> Path:
    """The book's ``_toc.yml`` without the parts whose every page is under :data:`ONLINE_ONLY`."""
    import yaml

    toc = yaml.safe_load((src / "_toc.yml").read_text())

    def online_only(part: dict) -> bool:
        files = [c.get("file", "") for c in part.get("chapters", [])]
        return bool(files) and all(f.startswith(ONLINE_ONLY) for f in files)

    toc["parts"] = [part for part in toc.get("parts", []) if not online_only(part)]
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(yaml.safe_dump(toc, sort_keys=False, allow_unicode=True))
    return target


def latex_errors(log: Path, context: int = 3) -> list[str]:
    """The error messages (``! ...`` and the lines after) of a LaTeX log."""
    if not log.is_file():
        return [f"no LaTeX log at {log}"]
    lines = log.read_text(errors="replace").splitlines()
    return [
        "\n".join(lines[i : i + context]) for i, line in enumerate(lines) if line.startswith("!")
    ]


def a4_edition(latex: Path, tex_name: str, env: dict[str, str]) -> Path:
    """The LaTeX folder ``latex`` copied and typeset again on A4 paper (the document class's
    ``letterpaper`` option replaced); returns the PDF."""
    a4 = latex.with_name(latex.name + "-a4")
    if a4.exists():
        shutil.rmtree(a4)
    shutil.copytree(latex, a4)
    tex = a4 / tex_name
    source, count = re.subn(
        r"(\\documentclass\[[^\]]*)\bletterpaper\b", r"\1a4paper", tex.read_text(), count=1
    )
    if count != 1:
        raise SystemExit(f"pdf: no letterpaper option in the document class of {tex}")
    tex.write_text(source)
    for stale in a4.glob(Path(tex_name).stem + ".*"):  # the letter edition's page numbers
        if stale.suffix != ".tex":
            stale.unlink()
    subprocess.run(["make", "-C", str(a4)], env=env, check=True, stdout=subprocess.DEVNULL)
    return a4 / Path(tex_name).with_suffix(".pdf").name


def build(src: Path, out: Path, executed: Path | None, html: Path | None, extra: list[str]) -> Path:
    sys.path[:0] = [str(src), str(src / "_ext")]
    from fdi_book import A4_NAME, PDF_NAME, publish_pdf

    start = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    cache_dir = out / f".jupyter_cache-{library_hash()}"
    for stale in out.glob(".jupyter_cache-*"):
        if stale != cache_dir:
            shutil.rmtree(stale)
    if executed is not None and executed.is_dir():
        library = max(p.stat().st_mtime for p in library_files())
        n = prime_cache(executed, cache_dir, newer_than=library)
        print(
            f"pdf: {n} notebooks executed by the HTML build ({executed}) in the cache", flush=True
        )
    else:
        print(
            "pdf: no executed notebooks given: the LaTeX build executes every chapter", flush=True
        )
    config = pdf_config(src, cache_dir.resolve(), out / "_config_pdf.yml")
    work = out / "build"
    latex = work / "_build" / "latex"
    if work.exists():  # a fresh Sphinx environment: the outputs may have changed, not the sources
        shutil.rmtree(work)
    env = dict(
        os.environ,
        LATEXOPTS="-interaction=nonstopmode -halt-on-error -file-line-error",
        PYTHONPATH=os.pathsep.join(filter(None, [str(src), os.environ.get("PYTHONPATH")])),
    )
    toc = pdf_toc(src, out / "_toc_pdf.yml")
    cmd = [
        str(Path(sys.executable).with_name("jupyter-book")),
        "build",
        str(src),
        "--config",
        str(config),
        "--toc",
        str(toc),
        "--path-output",
        str(work),
        "--builder",
        "pdflatex",
        "--warningiserror",
        "--nitpick",
        "--keep-going",
        *extra,
    ]
    print("+", " ".join(cmd), flush=True)
    done = subprocess.run(cmd, env=env)
    tex_name = Path(PDF_NAME).with_suffix(".tex").name
    built = latex / PDF_NAME
    if done.returncode != 0 or not built.is_file():
        for error in latex_errors(latex / Path(PDF_NAME).with_suffix(".log").name)[:20]:
            print(error, file=sys.stderr)
        raise SystemExit(
            f"pdf: the build failed (exit status {done.returncode}); LaTeX sources in {latex}"
        )
    pdf = out / PDF_NAME
    shutil.copy2(built, pdf)
    check = [
        sys.executable,
        str(REPO / "tools" / "check_pdf.py"),
        "--pdf",
        str(pdf),
        "--tex",
        str(latex / tex_name),
        "--src",
        str(src),
    ]
    if html is not None and (html / "index.html").is_file():
        check += ["--html", str(html)]
    print("+", " ".join(check), flush=True)
    subprocess.run(check, check=True)
    a4 = out / A4_NAME
    a4_pdf = a4_edition(latex, tex_name, env)
    shutil.copy2(a4_pdf, a4)
    print(f"pdf: the A4 edition {a4}")
    a4_check = check[: check.index("--pdf")] + [
        "--pdf",
        str(a4),
        "--tex",
        str(a4_pdf.with_suffix(".tex")),
        "--src",
        str(src),
    ]
    print("+", " ".join(a4_check), flush=True)
    subprocess.run(a4_check, check=True)
    if html is not None and (html / "index.html").is_file():
        publish_pdf(html, pdf)
        print(f"pdf: linked from the pages of {html}")
    print(f"pdf: {pdf} built in {time.perf_counter() - start:.0f} s")
    return pdf


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=["build"])
    parser.add_argument(
        "--src", type=Path, default=REPO, help="the book's sources (with _config.yml)"
    )
    parser.add_argument("--out", type=Path, default=REPO / "_build" / "pdf")
    parser.add_argument(
        "--executed",
        type=Path,
        default=REPO / "_build" / "jupyter_execute",
        help="the jupyter_execute folder of an HTML build of the same sources",
    )
    parser.add_argument(
        "--html",
        type=Path,
        default=REPO / "_build" / "html",
        help="the HTML build to put the PDF beside (if it exists)",
    )
    args, extra = parser.parse_known_args(argv)
    build(
        args.src.resolve(),
        args.out.resolve(),
        args.executed.resolve() if args.executed else None,
        args.html.resolve() if args.html else None,
        extra,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
