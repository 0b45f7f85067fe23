"""The installed wheel: it imports from outside the checkout, is the compiled abi3 module, and
its type stubs and docstrings cover every public name."""

import ast
import inspect
import os
import subprocess
import sys

import rlrs
import rlrs._rlrs as native


def public(module):
    return sorted(n for n in dir(module) if not n.startswith("_"))


def test_imports_from_anywhere_as_the_installed_abi3_module():
    out = subprocess.run([sys.executable, "-c", "import rlrs, rlrs._rlrs as m; print(rlrs.__version__, m.__file__)"],
                         cwd="/", capture_output=True, text=True, check=True).stdout.split()
    assert out[0] == rlrs.__version__
    assert out[1].endswith(".abi3.so") and "site-packages" in out[1], out[1]


def test_stubs_and_docstrings_cover_every_public_name():
    stub = os.path.join(os.path.dirname(rlrs.__file__), "__init__.pyi")
    tree = ast.parse(open(stub).read())
    declared = {}
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            declared[node.name] = {n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign)) and hasattr(n, "name")} | {
                n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
        elif isinstance(node, ast.AnnAssign):
            declared[node.target.id] = set()
    missing = [n for n in public(native) if n not in declared]
    assert not missing, f"not in {stub}: {missing}"
    for name in public(native):
        obj = getattr(native, name)
        if inspect.isclass(obj) or callable(obj):
            assert obj.__doc__ and obj.__doc__.strip(), f"{name} has no docstring"
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            for attr in public(obj):
                assert attr in declared[name], f"{name}.{attr} is not in the stub"
                assert getattr(obj, attr).__doc__, f"{name}.{attr} has no docstring"
