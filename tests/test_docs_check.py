"""The documentation checks that need no mkdocs (scripts/check_docs.py --sources), so CI catches a
regression without building the site; and the checks themselves, on planted faults.

Oracles: griffe (mkdocstrings' parser) gives every name of a numpydoc entry ``a, b : type`` the
first name's default and takes a choice set's first value as the default (read in griffe 2.4's
numpy parser); Sphinx roles are shown raw by mkdocstrings; pyproject.toml lists the extras.
"""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
spec = importlib.util.spec_from_file_location("check_docs", ROOT / "scripts" / "check_docs.py")
check_docs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(check_docs)


def test_sources_have_no_roles_wrong_defaults_or_missing_extras():
    assert check_docs.source_problems() == []


PLANTED = '''
def f(a, b=2, *, method=None, size_px=256):
    """One line.

    Parameters
    ----------
    a, b : float
        Grouped: the site would show ``b`` with ``a``'s default.
    method : {"mft", "fft"}, optional
        The site would show "mft" as the default.
    size_px : int, default 128
        Documented wrong.
    """
'''


def test_planted_faults_are_each_reported(tmp_path):
    path = tmp_path / "planted.py"
    path.write_text(PLANTED + '\n# see :func:`f`\n')
    problems = check_docs.docstring_default_problems([path]) + check_docs.role_problems([path])
    text = "\n".join(problems)
    assert "grouped parameters a, b" in text
    assert "parameter method default shown (a choice set's first value) as \"mft\", signature None" in text
    assert "parameter size_px default documented as 128, signature 256" in text
    assert "Sphinx role ':func:'" in text
    assert len(problems) == 4


def test_a_pip_extra_not_in_pyproject_is_reported(tmp_path):
    page = tmp_path / "planted.md"
    page.write_text("Install with `pip install -e '.[render]'` or `pip install -e \".[docs,test]\"`.\n")
    problems = check_docs.extras_problems([page], ROOT / "pyproject.toml")
    assert len(problems) == 1 and "'render'" in problems[0]


@pytest.mark.parametrize("documented, signature, same", [
    ('"wave"', "'wave'", True), ("0.25", "0.25", True), ("256", "256.0", True), ("550.0", "None", False),
    ('"mft"', "None", False), ("0.25", "256", False)])
def test_defaults_compare_by_value_not_spelling(documented, signature, same):
    assert check_docs.same_default(documented, signature) is same


PAGE = """<html><body><h1 id="psf">PSF</h1>
<h2 id="vissim.optics.psf.compute.compute_psf" class="doc doc-heading">compute_psf</h2>
<p>See :class:<code>PSF</code>, <code>README.md</code> and <code>docs/conventions.md</code>.</p>
<table><thead><tr><th>Name</th><th>Type</th><th>Description</th><th>Default</th></tr></thead><tbody>
<tr class="doc-section-item"><td><code>wavefront</code></td><td>Wavefront</td><td>x</td><td><em>required</em></td></tr>
<tr class="doc-section-item"><td><code>wavelength_nm</code></td><td>float</td><td>x</td><td><code>None</code></td></tr>
<tr class="doc-section-item"><td><code>size_px</code></td><td>int</td><td>x</td><td><code>0.25</code></td></tr>
<tr class="doc-section-item"><td><code>mode</code></td><td>str</td><td>x</td><td><code>"wave"</code></td></tr>
</tbody></table>
<a href="../missing/">gone</a> <a href="../psf/">here</a> <img src="x.png"> <img src="y.png" alt="a plot">
</body></html>"""


def test_the_site_check_reports_each_fault_on_a_rendered_page(tmp_path):
    # A page as mkdocstrings renders it, against vissim.compute_psf's real signature (size_px=256).
    page = tmp_path / "api" / "psf" / "index.html"
    page.parent.mkdir(parents=True)
    page.write_text(PAGE)
    for image in ("x.png", "y.png"):
        (page.parent / image).write_bytes(b"")
    problems = check_docs.site_problems(tmp_path)
    text = "\n".join(problems)
    assert "raw Sphinx role ':class:'" in text
    assert "compute_psf parameter size_px: shown default 0.25, signature 256" in text
    assert "link to ../missing/" in text and "../psf/" not in text.replace("../missing/", "")
    assert "image x.png has no alt text" in text and "y.png" not in text
    assert "names the file README.md" in text and "docs/conventions.md" not in text
    assert len(problems) == 5, problems
