"""Checks the documentation must pass; scripts/docs.sh runs them before and after mkdocs.

    python scripts/check_docs.py --sources        # docstrings and Markdown, no mkdocs needed
    python scripts/check_docs.py --site site      # the built site's HTML

Each problem is printed on one line and the exit status is 1 if there is any. What fails:

* a Sphinx role (``:func:`x```, ``:class:`x```, ...) in a docstring, a docs page or the rendered
  HTML: mkdocstrings renders Markdown and shows a role as written;
* a numpydoc parameter whose documented default differs from the signature's. mkdocstrings
  (griffe) gives every name of a grouped entry ``a, b : type`` the first name's default, and takes
  the first of a ``{'x', 'y'}`` choice set as the default, so both are checked from the sources;
  the site check compares every rendered parameter table with ``inspect.signature``;
* ``pip install`` of an extra that pyproject.toml does not declare;
* a link or a file name (``README.md``) in the site that is not on the site;
* an image without alt text.
"""

from __future__ import annotations

import argparse
import ast
import html
import importlib
import inspect
import re
import sys
import tomllib
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlparse

ROOT = Path(__file__).resolve().parent.parent
SPHINX_ROLES = ("class", "func", "mod", "meth", "attr", "data", "obj", "exc", "const", "ref", "doc", "term")
ROLE = re.compile(r":(?:py:)?(?:%s):(?=`|<code>)" % "|".join(SPHINX_ROLES))
NAME = r"\*{0,2}[\w.]+"
PARAMETER = re.compile(rf"^(?P<names>{NAME}(?:,\s*{NAME})*)(?:\s*:\s*(?P<type>.*))?$")
SECTION = re.compile(r"^(Parameters|Other Parameters)\n-+\n", re.M)
PIP_EXTRAS = re.compile(r"pip install[^\n`]*?['\"]?[.\w-]*\[(?P<extras>[\w,\s-]+)\]")


# -- sources ------------------------------------------------------------------------------
def role_problems(files: list[Path]) -> list[str]:
    """A Sphinx role anywhere in ``files`` (docstrings, comments or Markdown)."""
    return [f"{_rel(path)}:{n}: Sphinx role {m.group(0)!r} (write `name`; mkdocstrings shows roles raw)"
            for path in files for n, line in enumerate(path.read_text().splitlines(), 1) for m in ROLE.finditer(line)]


def _rel(path: Path) -> Path:
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


def _unquote(text: str) -> str:
    text = text.strip()
    return text[1:-1] if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"" else text


def same_default(documented: str, signature: str) -> bool:
    """Whether a documented default names the signature's (quotes and float spelling aside)."""
    a, b = _unquote(documented), _unquote(signature)
    if a == b:
        return True
    try:
        return float(a) == float(b)
    except ValueError:
        return False


def documented_parameters(docstring: str) -> list[tuple[list[str], str | None, str]]:
    """(names, documented default or None, how it is given) of each entry of the Parameters sections, read as griffe does."""
    entries = []
    for section in SECTION.finditer(docstring):
        for line in _section_lines(docstring[section.end():]):
            match = PARAMETER.match(line)
            if not match:
                continue
            names = [n.strip().lstrip("*") for n in match.group("names").split(",")]
            kind = (match.group("type") or "").strip()
            default, how = None, "documented"
            if kind.startswith("{") and "}" in kind:  # griffe: the first choice is the default
                default, how = kind[1:kind.rindex("}")].split(",")[0].strip(), "shown (a choice set's first value)"
            else:
                said = re.match(r"^.+,\s+default(?: |: |=)(?P<default>.+)$", kind)
                default = said.group("default") if said else None
            entries.append((names, default, how))
    return entries


def _section_lines(text: str) -> list[str]:
    """The unindented entry lines of one numpydoc section (up to the next section or the end)."""
    lines = []
    for line, following in zip(text.splitlines(), text.splitlines()[1:] + [""]):
        if re.fullmatch(r"-{3,}", following.strip()):
            break
        if line and not line[0].isspace():
            lines.append(line)
    return lines


def _signature_defaults(node: ast.AST) -> dict[str, str | None] | None:
    """name -> source of its default (None: required) of a function, or a class's ``__init__`` / fields."""
    if isinstance(node, ast.ClassDef):
        init = next((n for n in node.body if isinstance(n, ast.FunctionDef) and n.name == "__init__"), None)
        if init is not None:
            return _signature_defaults(init)
        return {n.target.id: (ast.unparse(n.value) if n.value is not None else None) for n in node.body
                if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)}
    args = node.args
    positional = args.posonlyargs + args.args
    defaults = [None] * (len(positional) - len(args.defaults)) + [ast.unparse(d) for d in args.defaults]
    out = {a.arg: d for a, d in zip(positional, defaults)}
    out.update({a.arg: (ast.unparse(d) if d is not None else None) for a, d in zip(args.kwonlyargs, args.kw_defaults)})
    return out


def docstring_default_problems(files: list[Path]) -> list[str]:
    """Grouped parameter entries, and documented defaults that differ from the signature's."""
    problems = []
    for path in files:
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            docstring = ast.get_docstring(node)
            if not docstring:
                continue
            signature = _signature_defaults(node)
            where = f"{_rel(path)}:{node.lineno} {node.name}"
            for names, default, how in documented_parameters(docstring):
                if len(names) > 1:
                    problems.append(f"{where}: grouped parameters {', '.join(names)} (the site gives every name "
                                    f"the first one's default); document each on its own line")
                    continue
                name = names[0]
                if default is None or name not in signature:
                    continue
                if signature[name] is None or not same_default(default, signature[name]):
                    problems.append(f"{where}: parameter {name} default {how} as {default}, signature {signature[name]}")
    return problems


def extras_problems(files: list[Path], pyproject: Path) -> list[str]:
    """``pip install ...[extra]`` naming an extra pyproject.toml does not declare."""
    declared = set(tomllib.loads(pyproject.read_text())["project"].get("optional-dependencies", {}))
    problems = []
    for path in files:
        for n, line in enumerate(path.read_text().splitlines(), 1):
            for match in PIP_EXTRAS.finditer(line):
                for extra in (e.strip() for e in match.group("extras").split(",")):
                    if extra and extra not in declared:
                        problems.append(f"{_rel(path)}:{n}: pip install extra {extra!r} is not in "
                                        f"pyproject.toml (extras: {', '.join(sorted(declared))})")
    return problems


def source_files(root: Path = ROOT) -> tuple[list[Path], list[Path]]:
    """(vissim's Python files, the docs' own pages and tutorial scripts; the copied reports left out)."""
    python = sorted((root / "vissim").rglob("*.py"))
    docs = [p for p in sorted((root / "docs").rglob("*")) if p.suffix in (".md", ".py")
            and "reports" not in p.relative_to(root / "docs").parts[:1] and p.name != "cli.md"]
    return python, docs


def source_problems(root: Path = ROOT) -> list[str]:
    """Every check that needs no site: roles, docstring defaults, pip extras."""
    python, docs = source_files(root)
    return (role_problems(python + docs) + docstring_default_problems(python)
            + extras_problems(docs + [root / "README.md"], root / "pyproject.toml"))


# -- the built site ------------------------------------------------------------------------
class _Page(HTMLParser):
    """Text, links, ``<code>`` texts and parameter tables (object id -> [(name, default)]) of a page."""

    def __init__(self):
        super().__init__()
        self.text, self.links, self.codes, self.tables, self.no_alt = [], [], [], {}, []
        self._object, self._stack, self._cells, self._row, self._code = None, [], [], None, None
        self._table_head = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag in ("h1", "h2", "h3", "h4") and (attrs.get("id") or "").startswith("vissim."):
            self._object = attrs["id"]
        if tag in ("a", "img", "link", "script"):
            target = attrs.get("href") or attrs.get("src")
            if target:
                self.links.append(target)
        if tag == "img" and not (attrs.get("alt") or "").strip():
            self.no_alt.append(attrs.get("src") or "?")
        if tag == "tr":
            self._row = []
        if tag in ("td", "th") and self._row is not None:
            self._row.append("")
        if tag == "code":
            self._code = ""

    def handle_endtag(self, tag):
        if tag == "code" and self._code is not None:
            self.codes.append(self._code)
            self._code = None
        if tag == "tr" and self._row is not None:
            row = [" ".join(c.split()) for c in self._row]
            if row[:1] == ["Name"] and "Default" in row:
                self._table_head = row
            elif self._table_head and len(row) == len(self._table_head) and self._object:
                self.tables.setdefault(self._object, []).append((row[0], row[self._table_head.index("Default")]))
            self._row = None
        if tag == "table":
            self._table_head = []

    def handle_data(self, data):
        self.text.append(data)
        if self._row is not None and self._row:
            self._row[-1] += data
        if self._code is not None:
            self._code += data


def _resolve(object_id: str):
    parts = object_id.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(object_id)


def _signature_default(obj, name: str) -> str | None:
    try:
        parameter = inspect.signature(obj).parameters[name]
    except (KeyError, TypeError, ValueError):
        return None
    if parameter.default is inspect.Parameter.empty:
        return "required"
    value = parameter.default
    return getattr(value, "__name__", None) or repr(value)


def _rendered_default(cell: str, expected: str, obj) -> bool:
    if cell == "required" or expected == "required":
        return cell == expected
    if re.fullmatch(r"[A-Za-z_][\w.]*", cell) and cell not in ("None", "True", "False"):
        module = sys.modules.get(getattr(obj, "__module__", ""), None)
        value = getattr(module, cell, None)  # a named constant (THESIS_FOCAL_LENGTH_MM)
        if value is not None:
            cell = getattr(value, "__name__", None) or repr(value)
    expected_tail = expected.rsplit(".", 1)[-1]  # np.float32 -> float32
    return same_default(cell, expected) or same_default(cell.rsplit(".", 1)[-1], expected_tail)


#: File names the pages mention as what vissim writes, not as pages to read.
WRITTEN_FILES = {"tables.md", "gap.md"}  # a campaign's tables, a population's comparison with published MTFs


def _page_exists(name: str, where: Path, root: Path) -> bool:
    """Whether a Markdown file a page names (``README.md``, ``docs/conventions.md``) is one of the site's pages."""
    if name in WRITTEN_FILES:
        return True
    docs = root / "docs"
    folders = (docs, docs / where.parent, docs / where.parent.parent)
    return any((f / name).is_file() for f in folders) or (name.startswith("docs/") and (root / name).is_file())


def site_problems(site: Path, root: Path = ROOT) -> list[str]:
    """Raw roles, parameter defaults against ``inspect.signature``, and links or file names not on the site."""
    problems = []
    pages = {p: p.read_text(errors="replace") for p in sorted(site.rglob("*.html"))}
    for path, text in pages.items():
        where = path.relative_to(site)
        if "/search/" in str(path) or path.name == "404.html":  # 404.html: links from the site's root
            continue
        for match in ROLE.finditer(text):
            problems.append(f"{where}: raw Sphinx role {match.group(0)!r} on the page")
        page = _Page()
        page.feed(text)
        for object_id, rows in page.tables.items():
            try:
                obj = _resolve(object_id)
            except (ImportError, AttributeError):
                continue
            for name, cell in rows:
                expected = _signature_default(obj, name)
                if expected is not None and not _rendered_default(cell, expected, obj):
                    problems.append(f"{where}: {object_id} parameter {name}: shown default {cell}, signature {expected}")
        for link in page.links:
            parsed = urlparse(link)
            if parsed.scheme or parsed.netloc or not parsed.path or link.startswith("data:"):
                continue
            target = (path.parent / unquote(parsed.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                problems.append(f"{where}: link to {link}, which is not on the site")
        problems += [f"{where}: image {src[:60]} has no alt text" for src in page.no_alt]
        for code in set(page.codes):
            name = html.unescape(code).strip()
            if re.fullmatch(r"[\w./-]+\.md", name) and not _page_exists(name, where, root):
                problems.append(f"{where}: names the file {name}, which is not on the site")
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sources", action="store_true", help="check docstrings and Markdown sources")
    parser.add_argument("--site", type=Path, help="check the built site in this folder")
    args = parser.parse_args(argv)
    problems = source_problems() if args.sources else []
    if args.site:
        sys.path.insert(0, str(ROOT))
        problems += site_problems(args.site)
    for problem in problems:
        print(f"check_docs: {problem}", file=sys.stderr)
    if not args.sources and not args.site:
        parser.error("give --sources, --site SITE or both")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
