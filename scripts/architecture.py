"""The parts of docs/architecture.md that are read off the tree: the layers and the packages.

    python scripts/architecture.py            # print them
    python scripts/architecture.py --write    # put them into docs/architecture.md

The layers are those ``tests/test_import_layers.py`` holds the imports to (:data:`LAYERS` there, the
one definition); the packages are every folder of ``precompute/`` and ``clothlight/`` with an
``__init__.py``, each with the first sentence of its docstring.  In the page they sit between
``<!-- generated: … -->`` and ``<!-- end generated -->`` lines, which ``--write`` replaces and the
test compares with this script's output.
"""

from __future__ import annotations

import argparse
import ast
import pathlib
import re
import sys

REPO = pathlib.Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:  # a script in scripts/: make the repository's packages importable
    sys.path.insert(0, str(REPO))

from tests.test_import_layers import LAYERS, ROOTS  # noqa: E402

PAGE = REPO / "docs" / "architecture.md"
BEGIN = "<!-- generated: python scripts/architecture.py --write -->"
END = "<!-- end generated -->"


def first_sentence(docstring: str) -> str:
    """The first sentence of a docstring's first paragraph, on one line, without reST markup."""
    paragraph = " ".join(docstring.strip().split("\n\n")[0].split())
    sentence = re.split(r"(?<=\.)\s+(?=[A-Z`(])", paragraph, maxsplit=1)[0].rstrip(".")
    return re.sub(r":\w+:`~?([^`]+)`", r"`\1`", sentence).replace("``", "`")


def packages() -> list[tuple[str, str]]:
    """(folder, first sentence of its docstring) of every package, in path order."""
    found = []
    for root in ROOTS:
        for init in sorted((REPO / root).rglob("__init__.py")):
            docstring = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))) or ""
            found.append((init.parent.relative_to(REPO).as_posix() + "/", first_sentence(docstring)))
    return found


def generated() -> str:
    """The page's generated part, markers included."""
    lines = [BEGIN, "", "| layer, bottom first | modules (a module belongs to its longest prefix) |", "| --- | --- |"]
    lines += [f"| {index}. {name} | {', '.join(f'`{prefix}`' for prefix in prefixes)} |"
              for index, (name, prefixes) in enumerate(LAYERS)]
    lines += ["", "| package | what it is |", "| --- | --- |"]
    lines += [f"| `{folder}` | {sentence} |" for folder, sentence in packages()]
    return "\n".join(lines + ["", END])


def page_with_generated(text: str) -> str:
    """``text`` (the page) with its generated part replaced by :func:`generated`."""
    start, end = text.index(BEGIN), text.index(END) + len(END)
    return text[:start] + generated() + text[end:]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--write", action="store_true", help=f"replace the generated part of {PAGE.name}")
    args = parser.parse_args(argv)
    if args.write:
        PAGE.write_text(page_with_generated(PAGE.read_text(encoding="utf-8")), encoding="utf-8")
    else:
        print(generated())
    return 0


if __name__ == "__main__":
    sys.exit(main())
