"""Sets one key of a commented YAML file by editing its line in place (scripts/tune, issue 13).

The files in config/ are read by people as much as by nodes: each key's comment says why it has its
value. Loading and dumping the YAML would drop every comment, so the tool changes only the value's text
on the key's own line (the comment after it stays, aligned where it was) and leaves every other line
as it was. A node's shipped YAML holds only the values that differ from its settings' declared defaults
(src/docking_settings): a key that is not in the file is added when the node's declaration declares it,
and refused otherwise: a misspelt key would otherwise be a silent no-op (the node ignores it and the
sweep measures nothing).

Keys nested in block mappings are addressed with dots (`chaser.cameras.ir.xyz_m`). Values are YAML
text (`5`, `0.25`, `paper_5point`, `[1, 2]`); the edited file is parsed again and must give the value
at that key, so a value that would break the file is refused too.
"""
import json
import pathlib
import re
import sys

import yaml

WORKSPACE = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(WORKSPACE / "src" / "docking_settings" / "src"))
from docking_settings.declarations import declared_defaults  # noqa: E402

# `  key: value  # comment` (block mapping entries only; a flow mapping `{a: 1}` is one value).
KEY_LINE = re.compile(r"^(?P<indent>[ ]*)(?P<key>[A-Za-z0-9_\-]+)[ ]*:(?P<rest>.*)$")


class KeyEditError(ValueError):
    """The key cannot be set as asked (not in the file, not a scalar line, a value YAML rejects)."""


def split_value_and_comment(rest):
    """Splits the text after `key:` into (value, comment): a comment starts at a `#` that follows a
    space outside quotes (YAML's rule), so `#` inside a quoted string stays part of the value."""
    quote = None
    for i, char in enumerate(rest):
        if quote:
            if char == quote:
                quote = None
        elif char in "'\"":
            quote = char
        elif char == "#" and (i == 0 or rest[i - 1] in " \t"):
            return rest[:i], rest[i:]
    return rest, ""


def find_key_line(lines, dotted_key):
    """Index of the line that holds `dotted_key`, found by following block indentation; None if the
    key is not there. Several lines with the same path (a malformed file) are refused."""
    wanted = dotted_key.split(".")
    stack = []  # (indent, key) of the enclosing block mappings
    found = []
    for index, line in enumerate(lines):
        stripped = line.strip()
        if not stripped or stripped.startswith("#") or stripped.startswith("---"):
            continue
        match = KEY_LINE.match(line)
        if not match:
            continue  # a list item or a continuation line: not a key of a block mapping
        indent = len(match.group("indent"))
        while stack and stack[-1][0] >= indent:
            stack.pop()
        path = [key for _, key in stack] + [match.group("key")]
        if path == wanted:
            found.append(index)
        stack.append((indent, match.group("key")))
    if len(found) > 1:
        raise KeyEditError("%s appears %d times (lines %s)" % (dotted_key, len(found), [i + 1 for i in found]))
    return found[0] if found else None


def value_at(document, dotted_key):
    """The value at a dotted key of a parsed YAML document (KeyError if absent)."""
    node = document
    for part in dotted_key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise KeyError(dotted_key)
        node = node[part]
    return node


def edited_line(line, new_value, dotted_key):
    """The line with its value replaced; the comment kept at its column when the new value fits."""
    body = line.rstrip("\n")
    match = KEY_LINE.match(body)
    value, comment = split_value_and_comment(match.group("rest"))
    if not value.strip():
        raise KeyEditError("%s has no value on its line (a mapping or a list below it): name a key inside it"
                           % dotted_key)
    key_part = body[:match.start("rest")]  # indent, key and colon, as written
    text = key_part + " " + new_value
    if comment:
        comment_column = len(key_part) + len(value)
        text = text.ljust(comment_column) if len(text) < comment_column else text + " "
        text += comment
    return text + line[len(body):]


def added_line(lines, dotted_key, new_value):
    """`lines` with `dotted_key: new_value` appended (an empty-mapping `{}` line dropped)."""
    kept = [line for line in lines if line.strip() != "{}"]
    if kept and not kept[-1].endswith("\n"):
        kept[-1] += "\n"
    return kept + ["%s: %s\n" % (dotted_key, new_value.strip())]


def set_key(path, dotted_key, new_value):
    """Sets `dotted_key` to the YAML text `new_value` in the file at `path`, in place; returns the old
    value text (a key the file did not hold: its declared default). Raises KeyEditError, naming the file and the key, when it cannot."""
    try:
        parsed_value = yaml.safe_load(new_value)
    except yaml.YAMLError as err:
        raise KeyEditError("%s: %s=%s: the value is not YAML (%s)" % (path, dotted_key, new_value, err))
    with open(path) as stream:
        lines = stream.readlines()
    try:
        index = find_key_line(lines, dotted_key)
    except KeyEditError as err:
        raise KeyEditError("%s: %s" % (path, err))
    defaults = (declared_defaults(path) or {}) if index is None else {}
    if index is None and dotted_key not in defaults:
        raise KeyEditError("%s: no key %s, and no settings declaration declares it (check its spelling and "
                           "nesting; nested keys with dots, e.g. chaser.cameras.ir.xyz_m)" % (path, dotted_key))
    if index is None:
        default = defaults[dotted_key]
        old_value = default if isinstance(default, str) else json.dumps(default)  # as YAML text
        lines = added_line(lines, dotted_key, new_value)
    else:
        old_value = split_value_and_comment(KEY_LINE.match(lines[index].rstrip("\n")).group("rest"))[0].strip()
        try:
            lines[index] = edited_line(lines[index], new_value.strip(), dotted_key)
        except KeyEditError as err:
            raise KeyEditError("%s: %s" % (path, err))
    text = "".join(lines)
    try:
        written = value_at(yaml.safe_load(text), dotted_key)
    except (yaml.YAMLError, KeyError) as err:
        raise KeyEditError("%s: %s=%s would break the file (%s)" % (path, dotted_key, new_value, err))
    if written != parsed_value:
        raise KeyEditError("%s: %s=%s reads back as %r" % (path, dotted_key, new_value, written))
    with open(path, "w") as stream:
        stream.write(text)
    return old_value
