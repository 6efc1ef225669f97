"""Every public function's and every kernel's documented parameters are its signature's.

numpydoc's own validation (``numpydoc.validate.validate``, as stumpy's docstring
check uses it) holds the public API of ``dir(dlasweep)`` and the methods of
``Cluster`` to the checks in ``CHECKS``; the numba kernels, which numpydoc cannot
introspect through their dispatchers, are parsed with ``numpydoc.docscrape`` and
compared with the signature of their Python function (``py_func``).
"""

import importlib
import inspect
import pkgutil
import re

import pytest
from numpydoc.docscrape import FunctionDoc
from numpydoc.validate import validate

import dlasweep
import dlasweep.kernels

CHECKS = {
    "GL08": "the object has no docstring",
    "PR01": "a parameter of the signature is not documented",
    "PR02": "a documented parameter is not in the signature",
    "PR03": "the parameters are documented in another order than the signature's",
    "PR04": "a parameter has no type",
    "PR06": "a type is spelt out ('integer', 'boolean', 'string') instead of int, bool, str",
    "PR10": "a parameter's colon has no space before it ('x: int')",
}
"""numpydoc's checks of the parameters and of a docstring's presence: what a reader of the API relies on.
The style checks (summary on one line, See Also, Examples, the ending full stop) are not held: the
docstrings are written to a house style of their own (a summary that may run on, no Examples)."""


def _public():
    """(name, object) of every public function and class of ``dir(dlasweep)``, and of Cluster's public methods."""
    for name in dir(dlasweep):
        obj = getattr(dlasweep, name)
        if not name.startswith("_") and (inspect.isfunction(obj) or inspect.isclass(obj)):
            yield name, obj
    for name, member in vars(dlasweep.Cluster).items():
        if not name.startswith("_") and (inspect.isfunction(member) or isinstance(member, property)):
            yield f"Cluster.{name}", getattr(dlasweep.Cluster, name)


def _qualified(name, obj):
    if name.startswith("Cluster."):
        return f"{dlasweep.Cluster.__module__}.Cluster.{name.split('.', 1)[1]}"
    return f"{obj.__module__}.{obj.__qualname__}"


PUBLIC = list(_public())


def test_the_public_api_is_all_there():
    names = {name for name, _ in PUBLIC}
    assert {"grow", "Cluster", "run_sweep", "open_sweep", "read_cluster", "summarise", "Cluster.n"} <= names


@pytest.mark.parametrize("name, obj", PUBLIC, ids=[name for name, _ in PUBLIC])
def test_public_parameters_are_documented_as_numpydoc_says(name, obj):
    errors = [(code, message) for code, message in validate(_qualified(name, obj))["errors"] if code in CHECKS]
    assert not errors, "\n".join(f"{name}: {code} ({CHECKS[code]}): {message}" for code, message in errors)


def _kernels():
    """(module name, name, Python function) of every numba kernel defined in ``dlasweep.kernels``."""
    package = dlasweep.kernels
    modules = [package] + [importlib.import_module(info.name)
                           for info in pkgutil.walk_packages(package.__path__, package.__name__ + ".")]
    for module in modules:
        for name, obj in vars(module).items():
            function = getattr(obj, "py_func", None)
            if function is not None and function.__module__ == module.__name__:
                yield module.__name__, name, function


KERNELS = list(_kernels())


def documented(function):
    """The parameter names of ``function``'s Parameters section, in order (``a, b : int`` names two)."""
    return [n.strip() for p in FunctionDoc(function)["Parameters"] for n in p.name.split(",") if n.strip()]


def arguments(function):
    return list(inspect.signature(function).parameters)


def test_the_kernels_are_found():
    names = {name for _, name, _ in KERNELS}
    assert {"walk_to_contact", "_grow", "step_to", "return_to_sphere"} <= names
    assert len(KERNELS) > 100


DOCUMENTED = [k for k in KERNELS if documented(k[2])]


@pytest.mark.parametrize("module, name, function", DOCUMENTED, ids=[f"{m}.{n}" for m, n, _ in DOCUMENTED])
def test_a_kernels_parameters_section_names_exactly_its_arguments(module, name, function):
    assert documented(function) == arguments(function), f"{module}.{name}"


def named_in_text(function):
    """The arguments of ``function`` that its docstring names nowhere (as a word of its own)."""
    doc = inspect.getdoc(function) or ""
    return [a for a in arguments(function) if not re.search(rf"(?<![\w.]){re.escape(a)}(?!\w)", doc)]


UNDOCUMENTED = [k for k in KERNELS if not documented(k[2])]


@pytest.mark.parametrize("module, name, function", UNDOCUMENTED, ids=[f"{m}.{n}" for m, n, _ in UNDOCUMENTED])
def test_a_kernel_without_a_parameters_section_names_every_argument(module, name, function):
    """A small helper may say its arguments in its text (``x``, ``dim``) rather than in a Parameters section."""
    assert not named_in_text(function), f"{module}.{name}: {named_in_text(function)} not named"


def _package_functions():
    """(qualified name, function) of every function and method defined in ``dlasweep`` outside the kernels."""
    for info in pkgutil.walk_packages(dlasweep.__path__, "dlasweep."):
        if info.name.startswith("dlasweep.kernels") or info.name == "dlasweep.__main__":
            continue
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            if getattr(obj, "__module__", None) != module.__name__:
                continue
            if inspect.isfunction(obj):
                yield f"{module.__name__}.{name}", obj
            elif inspect.isclass(obj):
                yield from ((f"{module.__name__}.{name}.{m}", f) for m, f in vars(obj).items() if inspect.isfunction(f))


def spelt(function):
    """The arguments of ``function`` as a Parameters section names them: ``*args``, ``**where``; no self."""
    star = {inspect.Parameter.VAR_POSITIONAL: "*", inspect.Parameter.VAR_KEYWORD: "**"}
    return [star.get(p.kind, "") + name for name, p in inspect.signature(function).parameters.items()
            if name not in ("self", "cls")]


SECTIONED = [(name, f) for name, f in _package_functions() if documented(f)]


def test_the_package_functions_are_found():
    assert len(SECTIONED) > 40


@pytest.mark.parametrize("name, function", SECTIONED, ids=[name for name, _ in SECTIONED])
def test_a_parameters_section_outside_the_kernels_names_exactly_its_arguments(name, function):
    """Every Parameters section of the package, private helpers' too, lists the signature, in its order."""
    assert documented(function) == spelt(function), name


def test_the_checks_can_fail():
    def f(a, b):
        """One line.

        Parameters
        ----------
        b : int
            B.
        c : int
            C.
        """
    assert documented(f) != arguments(f)
    assert named_in_text(f) == ["a"]
