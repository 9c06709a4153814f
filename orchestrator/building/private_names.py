"""Give the Python code inside a built FMU names private to its build.

Every pythonfmu FMU of one process shares one interpreter and one ``sys.modules``: two FMUs
that ship a package of the same name share the one imported first (its code, and its
``__path__`` into a folder the host may have deleted since).  So a built FMU's packages and its
slave script are renamed inside the archive, the way vendoring tools rename a vendored package:

* each package of :data:`PACKAGES` in ``resources/`` (``navcore``, ``fmushell`` and pythonfmu's
  own Python side) becomes ``<name>_<suffix>``, the suffix the hash of those packages' sources,
  so the FMUs of one build share them and a build that differs by one byte shares nothing;
* the slave script ``resources/<Model>.py`` becomes ``<Model>_<build>.py`` (``slavemodule.txt``
  names it), ``build`` the hash of the script and the packages (:func:`~orchestrator.building.
  build.source_hash`), so two builds of one model are two modules;
* the import statements that name those packages (``from navcore.x import y``, ``import
  fmushell``) are rewritten to the private names, binding the same local names, and the script
  first lets the shell point the packages already imported by another FMU of the same build at
  this FMU's folder (``fmushell.private_paths``: the other FMU's folder may be gone);
* ``resources/navfmu_build.json`` records the model, navfmu's version, the build hash and the
  private names (:data:`BUILD_FILE`; read by the FMU for its state identity and by the master
  to say which build ran).

The rewrite is checked: every rewritten file must compile, and an import form that cannot keep
its bound name (``import navcore.x`` without ``as``) is refused at build time.
"""
from __future__ import annotations

import ast
import hashlib
import io
import json
import tokenize
import zipfile
from pathlib import Path
from typing import Dict, List, Tuple

from navcore.core.state_format import BUILD_FILE, packed_content_hash

from ..errors import NavfmuError
from ..results.run_results import atomic_write

#: the packages an FMU ships under private names (the shell, the library, pythonfmu's Python side)
PACKAGES = ("fmushell", "navcore", "pythonfmu")
RESOURCES = "resources/"
SUFFIX_LENGTH = 16


def packages_suffix(files: Dict[str, bytes], packages=PACKAGES) -> str:
    """The private suffix of a build's packages: a hash of their files (archive names under
    ``resources/`` and bytes), the same for every FMU of one build."""
    return packed_content_hash(_package_files(files, packages))[:SUFFIX_LENGTH]


def _package_files(files: Dict[str, bytes], packages):
    """(name relative to resources, bytes) of the ``.py`` files of ``packages``."""
    return [(name[len(RESOURCES):], data) for name, data in files.items()
            if name.startswith(RESOURCES) and name.endswith(".py")
            and name[len(RESOURCES):].split("/", 1)[0] in packages]


def rewrite_imports(source: str, names: Dict[str, str], filename: str) -> str:
    """``source`` with every absolute import of a package in ``names`` (old -> new) rewritten to
    the new name, binding the same local names.  Raises NavfmuError on a form that cannot."""
    tree = ast.parse(source, filename)
    edits: List[Tuple[int, int, int, str]] = []    # (line, column, length, replacement)
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            top = node.module.split(".")[0]
            if top in names:
                line, col = _from_module_position(source, node)
                edits.append((line, col, len(top), names[top]))
        elif isinstance(node, ast.Import):
            edits += _import_edits(source, node, names, filename)
    lines = source.splitlines(keepends=True)
    for line, col, length, new in sorted(edits, reverse=True):
        text = lines[line - 1]
        lines[line - 1] = text[:col] + new + text[col + length:]
    result = "".join(lines)
    compile(result, filename, "exec")
    return result


def _from_module_position(source: str, node: ast.ImportFrom) -> Tuple[int, int]:
    """(line, column) of the module name after ``from`` in ``node``."""
    tokens = _statement_tokens(source, node)
    return tokens[1].start                          # tokens[0] is 'from'


def _import_edits(source, node: ast.Import, names, filename):
    """The edits of one ``import a, b.c as d`` statement."""
    tokens = _statement_tokens(source, node)
    edits = []
    i = 1                                           # past 'import'
    for alias in node.names:
        head = tokens[i]
        dotted = alias.name.count(".")
        i += 1 + 2 * dotted                         # the dotted name's tokens
        has_as = i < len(tokens) and tokens[i].string == "as"
        if has_as:
            i += 2
        i += 1                                      # the comma
        top = alias.name.split(".")[0]
        if top not in names:
            continue
        if has_as:
            edits.append((*head.start, len(top), names[top]))
        elif dotted == 0:
            edits.append((*head.start, len(top), f"{names[top]} as {top}"))
        else:
            raise NavfmuError(f"{filename}:{node.lineno}: 'import {alias.name}' cannot be given a "
                              f"private name; write 'from {alias.name.rsplit('.', 1)[0]} import "
                              f"{alias.name.rsplit('.', 1)[1]}' or 'import {alias.name} as ...'")
    return edits


def _statement_tokens(source: str, node: ast.stmt):
    """The tokens of the statement ``node``, from its first (``import`` or ``from``) on, with
    their positions in ``source``."""
    lines = source.splitlines(keepends=True)[node.lineno - 1:node.end_lineno]
    lines[0] = " " * node.col_offset + lines[0][node.col_offset:]   # what stands before it
    readline = io.StringIO("".join(lines)).readline
    tokens = []
    for tok in tokenize.generate_tokens(readline):
        if tok.type in (tokenize.NEWLINE, tokenize.ENDMARKER) or (
                tok.type == tokenize.OP and tok.string == ";"):
            break
        if tok.type in (tokenize.INDENT, tokenize.DEDENT, tokenize.NL, tokenize.COMMENT):
            continue
        tokens.append(tok._replace(start=(tok.start[0] + node.lineno - 1, tok.start[1])))
    return tokens


HEADER_BEGIN = "# navfmu: this build's packages (begin)\n"
HEADER_END = "# navfmu: this build's packages (end)\n"


def _adopt_header(shell: str) -> str:
    """The script's first statements: if another FMU of this build imported the packages, the
    shell checks that this FMU's copy is the same code and points them at this FMU's folder
    (the other one's may be gone) before anything is imported.  pythonfmu's loader puts the
    FMU's resources folder first on ``sys.path`` just before it imports or re-runs the script."""
    return (f"{HEADER_BEGIN}import sys as _navfmu_sys\n"
            f"if {shell!r} in _navfmu_sys.modules:\n"
            f"    _navfmu_sys.modules[{shell!r}].private_paths.adopt_folder(\n"
            f"        _navfmu_sys.path[0], globals())\n{HEADER_END}")


def _with_header(source: str, header: str, filename: str) -> str:
    """``source`` with ``header`` after its module docstring and ``from __future__`` imports
    (in place of an earlier header)."""
    if HEADER_BEGIN in source:
        head, _, rest = source.partition(HEADER_BEGIN)
        return head + header + rest.partition(HEADER_END)[2]
    tree = ast.parse(source, filename)
    after = 0
    for node in tree.body:
        is_doc = (isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
                  and isinstance(node.value.value, str) and after == 0)
        if is_doc or (isinstance(node, ast.ImportFrom) and node.module == "__future__"):
            after = node.end_lineno
        else:
            break
    lines = source.splitlines(keepends=True)
    return "".join(lines[:after]) + header + "".join(lines[after:])


def private_files(files: Dict[str, bytes], model: str, script: str, build: str,
                  packages: Dict[str, str], version: str) -> Dict[str, bytes]:
    """The files of an FMU (archive names -> bytes) with the packages ``packages`` (their
    current names -> base names) and the script ``resources/<script>.py`` under private names:
    the packages' suffix from their content, the script's module ``<model>_<build>``."""
    suffix = packages_suffix(files, tuple(packages))
    names = {old: f"{base}_{suffix}" for old, base in packages.items()}
    module = f"{model}_{build[:SUFFIX_LENGTH]}"
    old_script, new_script = RESOURCES + f"{script}.py", RESOURCES + f"{module}.py"
    if old_script not in files:
        raise NavfmuError(f"{model}: the FMU has no slave script {old_script}")
    out = {_renamed(name, names, old_script, new_script):
           _rewritten(name, data, names, old_script, module)
           for name, data in files.items() if name != RESOURCES + BUILD_FILE}
    shell = names[next(old for old, base in packages.items() if base == "fmushell")]
    text = _with_header(out[new_script].decode("utf-8"), _adopt_header(shell), old_script)
    compile(text, old_script, "exec")
    out[new_script] = text.encode("utf-8")
    identity = {"model": model, "version": version, "build": build, "module": module,
                "packages": {base: names[old] for old, base in packages.items()},
                "content_sha256": packed_content_hash(_package_files(out, tuple(names.values()))),
                "script_sha256": hashlib.sha256(out[new_script]).hexdigest()}
    out[RESOURCES + BUILD_FILE] = json.dumps(identity, indent=2, sort_keys=True).encode()
    return out


def make_private(fmu: Path, model: str, build: str, version: str) -> None:
    """Give the packages and the script of the freshly built ``fmu`` private names, in place,
    and write its :data:`BUILD_FILE`."""
    with zipfile.ZipFile(fmu) as src:
        files = {name: src.read(name) for name in src.namelist()}
    out = private_files(files, model, model, build, {p: p for p in PACKAGES}, version)

    def write(f):
        with zipfile.ZipFile(f, "w", zipfile.ZIP_DEFLATED) as dst:
            for name, data in out.items():
                info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
                info.external_attr = 0o644 << 16
                info.compress_type = zipfile.ZIP_DEFLATED
                dst.writestr(info, data)

    atomic_write(fmu, write, binary=True)


def _renamed(name: str, names: Dict[str, str], old_script: str, new_script: str) -> str:
    if name == old_script:
        return new_script
    if not name.startswith(RESOURCES):
        return name
    top, sep, tail = name[len(RESOURCES):].partition("/")
    return RESOURCES + names[top] + "/" + tail if sep and top in names else name


def _rewritten(name: str, data: bytes, names, old_script: str, module: str) -> bytes:
    if name == RESOURCES + "slavemodule.txt":
        return module.encode()
    top = name[len(RESOURCES):].split("/", 1)[0]
    if not name.endswith(".py") or (top not in names and name != old_script):
        return data
    return rewrite_imports(data.decode("utf-8"), names, name).encode("utf-8")


def read_build(fmu: Path):
    """The :data:`BUILD_FILE` of ``fmu`` as a dict, or None (an FMU not built by navfmu, or by
    a navfmu before private names)."""
    try:
        with zipfile.ZipFile(fmu) as z:
            return json.loads(z.read(RESOURCES + BUILD_FILE))
    except (OSError, KeyError, zipfile.BadZipFile, ValueError):
        return None


def changed_since_build(files: Dict[str, bytes], identity: dict) -> bool:
    """True if the Python code in ``files`` (an FMU's archive names -> bytes) is not what its
    build recorded (``identity``, its :data:`BUILD_FILE`)."""
    packages = tuple(identity["packages"].values())
    script = files.get(RESOURCES + f"{identity['module']}.py")
    return (packed_content_hash(_package_files(files, packages)) != identity["content_sha256"]
            or script is None or hashlib.sha256(script).hexdigest() != identity["script_sha256"])


def archive_changed_since_build(fmu: Path) -> bool:
    """:func:`changed_since_build` for the FMU file ``fmu`` (False without a build file)."""
    identity = read_build(fmu)
    if identity is None:
        return False
    with zipfile.ZipFile(fmu) as z:
        files = {n: z.read(n) for n in z.namelist() if n.endswith(".py")}
    return changed_since_build(files, identity)


def repack_if_changed(unzipdir: Path) -> bool:
    """Give the code of the navfmu FMU unpacked in ``unzipdir`` names of its own, in place, if
    it was changed after its build (so it runs its own code beside the unchanged FMUs of its
    build); returns True if it did.  An FMU without a :data:`BUILD_FILE` is left alone."""
    resources = Path(unzipdir) / RESOURCES
    try:
        identity = json.loads((resources / BUILD_FILE).read_text(encoding="utf-8"))
        code = _folder_files(resources, [resources / f"{identity['module']}.py"] + [
            p for package in identity["packages"].values()
            for p in (resources / package).rglob("*.py")])
        if not changed_since_build(code, identity):
            return False
    except (OSError, ValueError, KeyError, TypeError):
        return False
    files = _folder_files(resources, resources.rglob("*"))
    packages = {private: base for base, private in identity["packages"].items()}
    content = packed_content_hash(_package_files(files, tuple(packages)))
    script = hashlib.sha256(files.get(RESOURCES + f"{identity['module']}.py", b"")).hexdigest()
    build = hashlib.sha256(f"{content}\0{script}".encode()).hexdigest()
    out = private_files(files, identity["model"], identity["module"], build, packages,
                        identity["version"])
    for name in files:
        if name not in out:
            (Path(unzipdir) / name).unlink()
    for name, data in out.items():
        target = Path(unzipdir) / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
    return True


def _folder_files(resources: Path, paths) -> Dict[str, bytes]:
    """Archive names -> bytes of the files ``paths`` in the unpacked ``resources`` folder
    (compiled caches left out)."""
    return {RESOURCES + p.relative_to(resources).as_posix(): p.read_bytes()
            for p in paths if p.is_file() and "__pycache__" not in p.parts}
