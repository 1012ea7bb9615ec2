"""The keyword defaults of the module come from the C++ option structs: they equal the defaults
the esf command shows in its --help (taken from the same structs), and the type stubs name the
same parameters without spelling the defaults again."""

import ast
import math
import pathlib
import re

import pytest

import esf

STUBS = pathlib.Path(esf.__file__).with_name("_esf.pyi")

# (Python function, its parameter) -> (esf command, its option), for the parameters that both
# take from one C++ option struct.
SHARED = {
    ("describe", "samples"): ("describe", "--samples"),
    ("describe", "seed"): ("describe", "--seed"),
    ("describe", "sampler"): ("describe", "--sampler"),
    ("describe", "grid"): ("describe", "--grid"),
    ("describe_batch", "samples"): ("describe", "--samples"),
    ("describe_batch", "threads"): ("describe", "--threads"),
    ("segment", "grouping"): ("segment", "--grouping"),
    ("segment", "plane_distance"): ("segment", "--plane-distance"),
    ("segment", "min_height"): ("segment", "--min-height"),
    ("segment", "max_height"): ("segment", "--max-height"),
    ("segment", "cluster_tolerance"): ("segment", "--cluster-tolerance"),
    ("segment", "min_cluster_points"): ("segment", "--min-cluster-points"),
    ("segment", "seed"): ("segment", "--seed"),
    ("segment", "threads"): ("segment", "--threads"),
    ("Recognizer.scene", "grouping"): ("scene", "--grouping"),
    ("Recognizer.scene", "plane_distance"): ("scene", "--plane-distance"),
    ("Recognizer.scene", "cluster_tolerance"): ("scene", "--cluster-tolerance"),
    ("Recognizer", "k"): ("classify", "-k"),
    ("Recognizer", "samplings"): ("classify", "--samplings"),
    ("Recognizer", "vote"): ("classify", "--vote"),
    ("Recognizer", "threads"): ("classify", "--threads"),
    ("evaluate", "k"): ("eval", "-k"),
    ("evaluate", "samplings"): ("eval", "--samplings"),
    ("train", "descriptor"): ("train", "--descriptor"),
    ("train", "level"): ("train", "--level"),
    ("train", "samples"): ("train", "--samples"),
    ("train", "seed"): ("train", "--seed"),
    ("train", "noise"): ("train", "--noise"),
    ("train", "distance"): ("train", "--distance"),
    ("train", "max_distance"): ("train", "--max-distance"),
    ("train", "min_elevation"): ("train", "--min-elevation"),
    ("train", "max_elevation"): ("train", "--max-elevation"),
    ("train", "min_points"): ("train", "--min-points"),
    ("train", "occlusions"): ("train", "--occlusions"),
    ("render", "level"): ("render", "--level"),
    ("render", "fill"): ("render", "--fill"),
    ("render", "noise"): ("render", "--noise"),
    ("render", "seed"): ("render", "--seed"),
}


def _split_top_level(text):
    """Splits at the commas outside brackets."""
    parts, depth, start = [], 0, 0
    for i, c in enumerate(text):
        if c in "[(":
            depth += 1
        elif c in "])":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(text[start:i].strip())
            start = i + 1
    parts.append(text[start:].strip())
    return parts


def runtime_defaults(name):
    """{parameter: default} of a function or method as pybind11 writes its signature."""
    target = esf
    for part in name.split("."):
        target = getattr(target, part)
    if isinstance(target, type):
        target = target.__init__
    first = target.__doc__.strip().splitlines()[0]
    params = first[first.index("(") + 1:first.rindex(") ->")]
    defaults = {}
    for param in _split_top_level(params):
        if " = " in param:
            key, value = param.split(" = ", 1)
            defaults[key.split(":")[0].strip()] = ast.literal_eval(value)
    return defaults


def cli_defaults(cli, command):
    """{option: default text} of the options `esf COMMAND --help` shows a default for."""
    defaults = {}
    for line in cli(command, "--help").stdout.splitlines():
        # "  --name TYPE[:CHECKS]=DEFAULT   help"; the checks hold no '='
        match = re.match(r"\s+((?:-{1,2}[\w-]+,?)+)\s[^=]*=(\S+)", line)
        if match:
            for name in match.group(1).split(","):
                defaults[name] = match.group(2)
    return defaults


def same(python_value, cli_text):
    if isinstance(python_value, str):
        return python_value == cli_text
    return math.isclose(float(python_value), float(cli_text), rel_tol=1e-6)


def test_python_defaults_equal_the_commands(cli):
    help_defaults = {}
    mismatches = []
    for (function, param), (command, option) in SHARED.items():
        if command not in help_defaults:
            help_defaults[command] = cli_defaults(cli, command)
        python_value = runtime_defaults(function)[param]
        cli_text = help_defaults[command].get(option)
        assert cli_text is not None, f"esf {command} --help shows no default for {option}"
        if not same(python_value, cli_text):
            mismatches.append(f"{function}({param}={python_value!r}) but esf {command} "
                              f"{option}={cli_text}")
    assert not mismatches


def _stub_functions():
    """{name: ast function} of the stubs; methods as Class.method, __init__ as Class."""
    tree = ast.parse(STUBS.read_text())
    functions = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            functions[node.name] = node
        elif isinstance(node, ast.ClassDef):
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and not item.decorator_list:
                    key = node.name if item.name == "__init__" else f"{node.name}.{item.name}"
                    functions[key] = item
    return functions


@pytest.mark.parametrize("name", sorted(_stub_functions()))
def test_stubs_name_the_parameters_and_copy_no_default(name):
    node = _stub_functions()[name]
    args = node.args
    stub_defaults = dict(zip([a.arg for a in args.args[len(args.args) - len(args.defaults):]],
                             args.defaults))
    stub_defaults.update({a.arg: d for a, d in zip(args.kwonlyargs, args.kw_defaults) if d})
    runtime = runtime_defaults(name)
    assert set(stub_defaults) == set(runtime), name
    for param, default in stub_defaults.items():
        # `...` (the module's default) or None (the argument left out); never a copied value
        assert isinstance(default, ast.Constant) and default.value in (Ellipsis, None), param
        if default.value is None:
            assert runtime[param] is None, param
