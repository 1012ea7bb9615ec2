#!/usr/bin/env python3
"""Layering check: every #include in src/ and include/esf/ points to its own layer or one that
layer depends on, and each layer's CMakeLists.txt links only such layers.

    layering_test.py SOURCE_DIR

The layers and what each may use (docs/architecture.md); the uses are transitive."""
import pathlib
import re
import sys

USES = {
    "core": [],
    "io": ["core"],
    "mesh": ["io"],
    "render": ["mesh"],
    "shapes": ["mesh"],
    "descriptors": ["core"],
    "training": ["descriptors", "render"],
    "segmentation": ["core"],
    "recognition": ["training", "segmentation"],
    "evaluation": ["recognition"],
    "report": ["evaluation"],
    "demo": ["report", "shapes"],
}


def closure(layer):
    seen = {layer}
    todo = [layer]
    while todo:
        for used in USES[todo.pop()]:
            if used not in seen:
                seen.add(used)
                todo.append(used)
    return seen


def main():
    root = pathlib.Path(sys.argv[1])
    include = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)
    problems = []
    checked = 0
    for top in ("src", "include/esf"):
        for path in sorted((root / top).rglob("*")):
            if path.suffix not in (".cpp", ".hpp", ".inl"):
                continue
            rel = path.relative_to(root / top)
            if top == "include/esf" and rel.name == "esf.hpp" and len(rel.parts) == 1:
                continue  # the umbrella header includes every layer
            if len(rel.parts) < 2 or rel.parts[0] not in USES:
                problems.append(f"{top}/{rel}: not in a layer folder")
                continue
            allowed = closure(rel.parts[0])
            for name in include.findall(path.read_text()):
                parts = name.split("/")
                if parts[0] == "esf" and len(parts) > 2:
                    target = parts[1]
                elif len(parts) > 1 and parts[0] in USES:
                    target = parts[0]
                else:
                    continue  # a system or third-party header
                checked += 1
                if target not in allowed:
                    problems.append(f"{top}/{rel}: includes {name}, but {rel.parts[0]} does not "
                                    f"use {target}")
    link = re.compile(r"\besf_(" + "|".join(USES) + r")\b")
    for layer in USES:
        cmake = root / "src" / layer / "CMakeLists.txt"
        if not cmake.exists():
            problems.append(f"src/{layer}: no CMakeLists.txt")
            continue
        for target in link.findall(cmake.read_text()):
            if target not in closure(layer):
                problems.append(f"src/{layer}/CMakeLists.txt: links esf_{target}, but {layer} "
                                f"does not use {target}")
    for line in problems:
        print(line)
    print(f"{checked} project includes checked, {len(problems)} outside the layer order")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
