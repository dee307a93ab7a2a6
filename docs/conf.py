"""Sphinx configuration of the minkq documentation site (built by `./build.sh docs`).

docs/build.sh runs Doxygen, cargo doc and the figure script first and names their output
folders in the environment: MINKQ_DOCS_BUILD (default: build-docs at the repository root)
holds doxygen/xml (the C reference, through breathe), rust/ (cargo doc's output, copied into
the site as rust/) and figures/ (the guarantee's figures, SVG). The Python reference is
autodoc on the installed minkq package (docs/build.sh installs the wheel into its venv).
"""
import os
from pathlib import Path

root = Path(__file__).resolve().parent.parent
build = Path(os.environ.get("MINKQ_DOCS_BUILD", root / "build-docs"))

project = "minkq"
author = "the minkq authors"
copyright = "the minkq authors"
release = (root / "VERSION").read_text().strip()
version = release

extensions = ["myst_parser", "breathe", "sphinx.ext.autodoc"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_tools", "tutorials/*.py"]
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence", "deflist"]
# The bench programs write their tables with H1 then H3 sections (bench/results/*.md, included
# as they are): a heading jump is a matter of style there, not a fault of the site.
suppress_warnings = ["myst.header"]

# C reference: Doxygen's XML of capi/minkq.h, capi/minkq_async.h and mpi/minkq_mpi.h
# (docs/_tools/Doxyfile).
breathe_projects = {"minkq": str(build / "doxygen" / "xml")}
breathe_default_project = "minkq"
breathe_domain_by_extension = {"h": "c"}
c_id_attributes = []

# Python reference: the documented members in the order of the source.
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "description"

html_theme = "alabaster"
html_title = f"minkq {release}"
html_static_path = []
# cargo doc's output (build/rust/rust/...) lands in the site as rust/; the figures as figures/.
html_extra_path = [str(build / "rust")]
figures = build / "figures"

# The benchmark results (bench/results/*.md, written by the bench programs) as pages of the
# site: one page each under _generated/results/, including the file as it is, with the plots
# bench/plot.py drew beside it.
results = root / "bench" / "results"
pages = root / "docs" / "_generated" / "results"
pages.mkdir(parents=True, exist_ok=True)
for stale in pages.glob("*.md"):
    stale.unlink()
for table in sorted(results.glob("*.md")):
    text = f"```{{include}} ../../../bench/results/{table.name}\n```\n"
    for plot in sorted(results.glob(f"{table.stem}_*.png")):
        text += f"\n![{plot.stem}](../../../bench/results/{plot.name})\n"
    (pages / table.name).write_text(text)
