#!/usr/bin/env python3
"""Writes the C++ header of a settings declaration (build step: docking_settings_generate() in CMake).
    generate_settings.py DECLARATION.yaml OUTPUT.h SOURCE_NAME"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "src"))
from docking_settings.cpp import header  # noqa: E402
from docking_settings.declarations import Declaration, DeclarationError  # noqa: E402


def main():
    declaration_path, output, source_name = sys.argv[1:4]
    try:
        declaration = Declaration(declaration_path)
    except DeclarationError as error:
        sys.exit("generate_settings: %s" % error)
    text = header(declaration, source_name)
    out = pathlib.Path(output)
    if not out.exists() or out.read_text() != text:  # unchanged: no rebuild of its users
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)


if __name__ == "__main__":
    main()
