#!/usr/bin/env python3
"""Writes python/hapticd/_native.pyi, the type stub of the pybind11 module hapticd._native, from a
build: mypy's stubgen (Debian 12's, mypy 1.0) reads the built module, and the fixes below make its
output correct where stubgen cannot read pybind11's signatures. With --check it writes nothing and
fails, printing a diff, if the checked-in stub differs from a fresh one (whitespace aside).

Usage: /usr/bin/python3 python/generate_stubs.py [--check] BUILD_DIR
       (the module is BUILD_DIR/python/hapticd/_native*.so; docs/python.md, "Type stubs")

The fixes, each for something stubgen 1.0 reads wrongly or not at all:
- a property's type is its getter's return type from the getter's signature (stubgen takes it from
  the property's own docstring, reading "0: the server's own" as the type `0`); a field whose
  setter takes more than its getter returns (any sequence of 3 numbers for a float64 array of 3)
  becomes a property with a setter;
- pybind11's names for NumPy values become numpy.typing's: a returned array is
  NDArray[numpy.float64] (NDArray[numpy.uint32] for mesh indices), an array argument ArrayLike;
- a spec's keyword constructor (`**kwargs` to pybind11) takes its writable fields by keyword, each
  typed as its setter takes it, and Client() takes ClientConfig's the same way;
- static methods (OperatorInput.follow, push, ...) get their signatures and @staticmethod;
- `hapticd.` qualifiers go (the package renames its classes' __module__ to `hapticd`), as do the
  enums' private `__entries` and the `__init__(*args, **kwargs)` of classes Python cannot make
  (handles); `__eq__` takes any object, `__enter__` returns the class itself, StateFlag's
  arithmetic returns int, a bare dict is Dict[Any, Any], and the few things pybind11 can only call
  `object` or `list` are named in TYPE_OVERRIDES and EXTRA_MEMBERS below.
"""

import argparse
import difflib
import importlib
import inspect
import re
import sys
import tempfile
from pathlib import Path

STUB = Path(__file__).resolve().parent / "hapticd" / "_native.pyi"
MODULE = "hapticd._native"

HEADER = '''"""Type stub of hapticd._native, the pybind11 module under the package hapticd.

Made by python/generate_stubs.py from stubgen's output; do not edit by hand: change the bindings
(python/src) or that script, and regenerate (docs/python.md, "Type stubs").
"""
'''

# What pybind11 can only call `object` or a bare list: "Class.member" (a property's type) or
# "Class.method.parameter".
TYPE_OVERRIDES = {
    "AppliedScene.objects": "List[ObjectHandle]",
    "AppliedScene.fields": "List[FieldHandle]",
    "Client.on_state.callback": "Optional[Callable[[State], object]]",
    "Client.on_event.callback": "Optional[Callable[[Event], object]]",
    "Client.on_connection.callback": "Optional[Callable[[ConnectionChange], object]]",
    "OperatorInput.push_recorded.samples": "ArrayLike",
    "Client.record.path": "Union[str, PathLike[str]]",
}

# Attributes set on instances at run time (module.cpp, raise()).
EXTRA_MEMBERS = {
    "Error": ["code: ErrorCode"],
    "VersionMismatchError": ["client_version: int", "server_version: int"],
}

# Constructors whose **kwargs are the writable fields of another class.
KWARGS_FROM = {"Client": "ClientConfig"}

ARITHMETIC = {"__and__", "__or__", "__xor__", "__rand__", "__ror__", "__rxor__", "__invert__"}
LINE_LIMIT = 100


def split_top_level(text, separator=","):
    """`text` split at `separator` outside brackets, each part stripped."""
    parts, depth, start = [], 0, 0
    for i, char in enumerate(text):
        if char in "([":
            depth += 1
        elif char in ")]":
            depth -= 1
        elif char == separator and depth == 0:
            parts.append(text[start:i].strip())
            start = i + 1
    if text[start:].strip():
        parts.append(text[start:].strip())
    return parts


def python_type(text, argument):
    """A type as pybind11 writes it, as the stub writes it: an argument (`argument`) or a result."""
    text = text.replace("hapticd._native.", "").replace("hapticd.", "")
    if argument:
        text = re.sub(r"numpy\.ndarray\[[^\]]*\](?: \([^)]*\))?", "ArrayLike", text)
    else:
        text = re.sub(r"numpy\.ndarray\[(numpy\.\w+)\]", r"NDArray[\1]", text)
        # Vec3 and Quaternion's casters: "numpy.ndarray[3]", "numpy.ndarray[4] (w, x, y, z)".
        text = re.sub(r"numpy\.ndarray\[\d+\](?: \([^)]*\))?", "NDArray[numpy.float64]", text)
    text = re.sub(r"(?<![\w.\[])dict(?![\w\[])", "Dict[Any, Any]", text)  # __deepcopy__'s memo
    return re.sub(r",(?=\S)", ", ", text)


def signature_types(function):
    """(parameter types, result type) from a pybind11 function's first docstring line,
    "(self: X, arg0: T) -> R"."""
    first = (function.__doc__ or "").splitlines()[0]
    match = re.fullmatch(r".*?\((.*)\) -> (.+)", first)
    if not match:
        raise SystemExit(f"generate_stubs: cannot read the signature {first!r}")
    parameters = [part.split(": ", 1)[1] for part in split_top_level(match.group(1)) if ": " in part]
    return parameters, match.group(2)


class Parameter:
    def __init__(self, text):
        self.star = ""
        if text.startswith("**"):
            self.star, text = "**", text[2:]
        elif text.startswith("*"):
            self.star, text = "*", text[1:]
        self.default = text.endswith(" = ...")
        text = text.removesuffix(" = ...")
        self.name, _, self.type = text.partition(": ")

    def render(self):
        text = self.star + self.name + (f": {self.type}" if self.type else "")
        return text + (" = ..." if self.default else "")


def render_def(indent, name, parameters, result):
    """A `def` line, or several (one parameter a line) where one would be too long."""
    rendered = [p if isinstance(p, str) else p.render() for p in parameters]
    line = f"{indent}def {name}({', '.join(rendered)}) -> {result}: ..."
    if len(line) <= LINE_LIMIT:
        return [line]
    return ([f"{indent}def {name}("] + [f"{indent}    {p}," for p in rendered]
            + [f"{indent}) -> {result}: ..."])


class Fixer:
    def __init__(self, module):
        self.module = module

    def writable_fields(self, cls):
        """(name, setter argument type) for each field of a struct class that has a setter."""
        fields = []
        for name in cls.__dict__.get("_fields", ()):
            prop = cls.__dict__[name]
            if prop.fset is not None:
                fields.append((name, self.setter_type(cls, name)))
        return fields

    def getter_type(self, cls, name):
        override = TYPE_OVERRIDES.get(f"{cls.__qualname__}.{name}")
        if override:
            return override
        return python_type(signature_types(cls.__dict__[name].fget)[1], argument=False)

    def setter_type(self, cls, name):
        prop = cls.__dict__[name]
        argument = signature_types(prop.fset)[0][-1]
        if argument == "object" and "NDArray" in self.getter_type(cls, name):
            return "ArrayLike"  # MeshSpec.vertices and the like: converted by NumPy
        return python_type(argument, argument=True)

    def keyword_parameters(self, cls):
        return [Parameter(f"{name}: {typ} = ...") for name, typ in self.writable_fields(cls)]

    def fix_def(self, indent, cls, line):
        """One stubgen `def` line of class `cls` (None: the module) as the stub's line(s)."""
        match = re.fullmatch(r"def (\w+)\((.*)\) -> (.+): \.\.\.", line.strip())
        if not match:
            raise SystemExit(f"generate_stubs: cannot read stubgen's line {line.strip()!r}")
        name, parameters, result = match.group(1), split_top_level(match.group(2)), match.group(3)
        parameters = [Parameter(p) for p in parameters]
        qualified = f"{cls.__qualname__}.{name}" if cls is not None else name
        result = python_type(result, argument=False)
        for parameter in parameters:
            if parameter.type:
                parameter.type = TYPE_OVERRIDES.get(f"{qualified}.{parameter.name}",
                                                    python_type(parameter.type, argument=True))
        if cls is not None:
            if name == "__init__" and "_fields" in cls.__dict__:
                fields = self.keyword_parameters(cls)
                parameters = [parameters[0]] + (["*"] + fields if fields else [])
            elif name == "__init__" and cls.__name__ in KWARGS_FROM:
                source = getattr(self.module, KWARGS_FROM[cls.__name__])
                parameters = [p for p in parameters if p.star != "**"]
                parameters += ["*"] + self.keyword_parameters(source)
            elif name == "__init__" and [p.render() for p in parameters] == ["self", "*args",
                                                                            "**kwargs"]:
                return []  # no constructor: handles and AppliedScene come only from a Client
            elif name == "__eq__":
                parameters = [parameters[0], Parameter("other: object")]
            elif name == "__enter__":
                result = cls.__qualname__
            elif name == "__exit__":
                parameters = [parameters[0], Parameter("*args: object")]
            elif name in ARITHMETIC and result == "object":
                result = "int"
        return render_def(indent, name, parameters, result)

    def static_method(self, indent, cls, name):
        """@staticmethod stubs for `cls.name` from its pybind11 docstring (overloads and all)."""
        from mypy.stubgenc import DocstringSignatureGenerator

        function = getattr(cls, name)
        signatures = DocstringSignatureGenerator().get_function_sig(function, MODULE, name)
        lines = []
        for signature in signatures:
            parameters = []
            for arg in signature.args:
                parameter = Parameter(arg.name + (" = ..." if arg.default else ""))
                if arg.type:
                    parameter.type = TYPE_OVERRIDES.get(f"{cls.__qualname__}.{name}.{arg.name}",
                                                        python_type(arg.type, argument=True))
                parameters.append(parameter)
            lines.append(f"{indent}@staticmethod")
            if len(signatures) > 1:
                lines.append(f"{indent}@overload")
            lines += render_def(indent, name, parameters, python_type(signature.ret_type, False))
        return lines

    def fix(self, raw):
        lines = raw.splitlines()
        while lines and (not lines[0] or lines[0].startswith(("from ", "import "))):
            lines.pop(0)
        out = []
        stack = []  # (indent of the class's body, class)
        i = 0
        while i < len(lines):
            line = lines[i]
            i += 1
            stripped = line.strip()
            indent = line[: len(line) - len(line.lstrip())]
            while stack and stripped and len(indent) < stack[-1][0]:
                stack.pop()
            cls = stack[-1][1] if stack else None

            match = re.fullmatch(r"class (\w+)(\(.*\))?:( \.\.\.)?", stripped)
            if match:
                owner = cls if cls is not None else self.module
                new = getattr(owner, match.group(1))
                bases = python_type(match.group(2) or "", argument=False)
                extra = EXTRA_MEMBERS.get(new.__qualname__)
                if match.group(3) and not extra:
                    out.append(f"{indent}class {match.group(1)}{bases}: ...")
                    continue
                out.append(f"{indent}class {match.group(1)}{bases}:")
                out += [f"{indent}    {member}" for member in extra or []]
                if not match.group(3):
                    stack.append((len(indent) + 4, new))
                continue

            if cls is None:
                if stripped.startswith("def "):
                    out += self.fix_def(indent, None, stripped)
                else:
                    out.append(python_type(line, argument=False) if stripped else line)
                continue

            if stripped.startswith("__entries: "):
                continue
            if stripped.startswith("__hash__: ClassVar[None]"):  # unhashable, as typeshed says it
                out.append(f"{indent}__hash__: ClassVar[None]  # type: ignore[assignment]")
                continue
            if stripped.startswith("__members__: "):
                out.append(f"{indent}__members__: ClassVar[Dict[str, {cls.__qualname__}]]")
                continue
            if stripped.startswith("_fields: "):
                out.append(f"{indent}_fields: ClassVar[Tuple[str, ...]]")
                continue
            if stripped == "@property":  # a read-only property: its def follows
                name = re.match(r"def (\w+)", lines[i].strip()).group(1)
                i += 1
                out += [f"{indent}@property",
                        f"{indent}def {name}(self) -> {self.getter_type(cls, name)}: ..."]
                continue
            match = re.fullmatch(r"(\w+): (?!ClassVar\[)(.+)", stripped)
            if match and isinstance(cls.__dict__.get(match.group(1)), property):
                name = match.group(1)
                getter, setter = self.getter_type(cls, name), self.setter_type(cls, name)
                if getter == setter:
                    out.append(f"{indent}{name}: {getter}")
                else:
                    out += [f"{indent}@property",
                            f"{indent}def {name}(self) -> {getter}: ...",
                            f"{indent}@{name}.setter",
                            f"{indent}def {name}(self, value: {setter}) -> None: ..."]
                continue
            if stripped.startswith("def "):
                name = re.match(r"def (\w+)", stripped).group(1)
                if isinstance(inspect.getattr_static(cls, name), staticmethod):
                    out += self.static_method(indent, cls, name)
                else:
                    out += self.fix_def(indent, cls, stripped)
                continue
            if stripped == "@overload":
                out.append(line)
                continue
            out.append(python_type(line, argument=False))
        return HEADER + "\n" + imports_for("\n".join(out)) + "\n" + "\n".join(out).rstrip() + "\n"


def imports_for(body):
    """The import lines the stub's body needs."""
    typing_names = [name for name in ("Any", "Callable", "ClassVar", "Dict", "List", "Optional",
                                      "Tuple", "Union", "overload")
                    if re.search(rf"\b{name}\b", body)]
    lines = []
    if re.search(r"\bPathLike\b", body):
        lines.append("from os import PathLike")
    if typing_names:
        lines.append(f"from typing import {', '.join(typing_names)}")
        lines.append("")
    if re.search(r"\bnumpy\.", body):
        lines.append("import numpy")
    numpy_typing = [name for name in ("ArrayLike", "NDArray") if re.search(rf"\b{name}\b", body)]
    if numpy_typing:
        lines.append(f"from numpy.typing import {', '.join(numpy_typing)}")
    return "\n".join(lines) + "\n"


def normalized(text):
    """`text` without the whitespace that does not separate two names, and without trailing
    commas: a rewrapped or reindented stub compares equal."""
    text = re.sub(r"\s+", " ", text).strip()
    text = re.sub(r" (?=\W)|(?<=\W) ", "", text)
    return re.sub(r",([)\]])", r"\1", text)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("build_dir", type=Path)
    parser.add_argument("--check", action="store_true",
                        help="compare with the checked-in stub instead of writing it")
    args = parser.parse_args()
    package_root = (args.build_dir / "python").resolve()
    if not any((package_root / "hapticd").glob("_native*.so")):
        raise SystemExit(f"generate_stubs: no built module in {package_root}/hapticd "
                         "(cmake --build BUILD_DIR --target haptic_python)")
    sys.path.insert(0, str(package_root))
    module = importlib.import_module(MODULE)
    if not Path(module.__file__).resolve().is_relative_to(package_root):
        raise SystemExit(f"generate_stubs: imported {module.__file__}, not the build's module")

    from mypy.stubgen import main as stubgen

    with tempfile.TemporaryDirectory() as out:
        stubgen(["--quiet", "-m", MODULE, "-o", out])
        raw = (Path(out) / "hapticd" / "_native.pyi").read_text()
    fresh = Fixer(module).fix(raw)

    if not args.check:
        STUB.write_text(fresh)
        print(f"generate_stubs: wrote {STUB}")
        return 0
    current = STUB.read_text() if STUB.exists() else ""
    if normalized(current) == normalized(fresh):
        print(f"generate_stubs: {STUB.name} is up to date")
        return 0
    sys.stdout.writelines(difflib.unified_diff(
        current.splitlines(keepends=True), fresh.splitlines(keepends=True),
        fromfile=f"{STUB} (checked in)", tofile="from the build"))
    print(f"\ngenerate_stubs: {STUB.name} is out of date with the built module. Regenerate it with\n"
          f"  {sys.executable} python/generate_stubs.py {args.build_dir}\n"
          "from the source tree, review the diff, and commit it.")
    return 1


if __name__ == "__main__":
    sys.exit(main())
