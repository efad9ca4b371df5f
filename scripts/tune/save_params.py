#!/usr/bin/env python3
"""Writes the values a node runs with back into its YAML in config/, after live tuning with dynparam.

  rosrun dynamic_reconfigure dynparam set /disparity_detector min_blob_area_px 350
  scripts/tune/save_params.py /disparity_detector [--dry-run] [--config-dir DIR]

Which YAML a node loads is read from launch/*.launch (its <rosparam command="load" file=...>), so the
launch files stay the one home of that mapping. The node's current values are asked of its
dynamic_reconfigure server (what `dynparam get` shows). A node whose settings are declared
(src/*/settings/*.yaml claims its YAML) keeps in its YAML only what differs from the declared defaults:
a live value that differs is changed on its line, or added as a line of its own; one back at its default
has its line removed. Every other line stays as it was (comments, blank lines, key order: a YAML dump
would lose them). For a node without a declaration, only keys already in the YAML are changed, and live
parameters the file lacks are reported. A unified diff is printed; --dry-run prints it only.

Exit status: 0 written (or nothing to write), 1 an error (no ROS master, node not running, no YAML
mapped to the node, a key nested or repeated in the YAML), 2 bad arguments.
"""
import argparse
import difflib
import json
import math
import os
import pathlib
import re
import sys
import tempfile
import xml.etree.ElementTree as ElementTree

import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
LAUNCH_DIR = ROOT / "launch"
CONFIG_DIR = ROOT / "config"
sys.path.insert(0, str(ROOT / "src" / "docking_settings" / "src"))
from docking_settings.declarations import declared_defaults  # noqa: E402

# A top-level `key: value` line; the key is a ROS parameter name (no quoting, no nesting).
TOP_LEVEL_KEY = re.compile(r"^(?P<key>[A-Za-z_][A-Za-z0-9_]*)(?P<colon>[ \t]*:)(?P<rest>.*)$")
# The empty mapping of a YAML that overrides no default.
EMPTY_MAPPING = re.compile(r"^\{\}[ \t]*(#.*)?$")
# Value texts that are not a one-line scalar: flow collections, block scalars, anchors, aliases, tags.
NOT_SCALAR_START = ("[", "{", "|", ">", "&", "*", "!")


class SaveError(Exception):
    """A condition the user must fix (wrong node, node down, a YAML this tool will not edit safely)."""


# --- Which YAML each node loads (launch files) ------------------------------------------------------

def yaml_loads(rosparams):
    """The YAML file names of the <rosparam command="load" file="*.yaml"> among rosparams."""
    return [pathlib.PurePosixPath(r.get("file")).name for r in rosparams
            if r.get("command", "load") == "load" and (r.get("file") or "").endswith(".yaml")]


def yaml_of_nodes(launch_dir=LAUNCH_DIR):
    """{node name: YAML file name} from launch_dir: every <node> that loads exactly one YAML from the
    config folder into its private namespace, and every nodelet of a launch file whose YAML is loaded
    into its name by a launch-level <rosparam file=... ns="NAME"/> (perception.launch: the nodelets run
    in one process, perception_host, and their parameters sit under their names). A node loading several
    such files, or different files in different launch files, maps to None: which file holds a key would
    be a guess."""
    mapping = {}

    def add(name, files):
        if not files:
            return
        found = files[0] if len(files) == 1 else None
        mapping[name] = found if mapping.get(name, found) == found else None

    for launch in sorted(pathlib.Path(launch_dir).glob("*.launch")):
        root = ElementTree.parse(launch).getroot()
        inside_nodes = set()
        for node in root.iter("node"):
            inside_nodes.update(node.iter("rosparam"))
            name = node.get("name", "")
            if not name or "$(" in name:
                continue
            add(name, yaml_loads(r for r in node.iter("rosparam") if not r.get("ns")))
        by_namespace = {}
        for r in root.iter("rosparam"):
            ns = r.get("ns") or ""
            if r in inside_nodes or not ns or "$(" in ns or "/" in ns:
                continue
            by_namespace.setdefault(ns, []).extend(yaml_loads([r]))
        for name, files in by_namespace.items():
            add(name, files)
    return mapping


def yaml_path_for(node, config_dir, launch_dir=LAUNCH_DIR):
    """The YAML that `node` (a resolved name; the launch files know its last component) loads."""
    mapping = yaml_of_nodes(launch_dir)
    base = node.rstrip("/").rsplit("/", 1)[-1]
    if base not in mapping:
        known = ", ".join(sorted(n for n, f in mapping.items() if f))
        raise SaveError(f"{node}: unknown node: no launch file in {launch_dir} loads a YAML into it "
                        f"(nodes with a YAML: {known})")
    if mapping[base] is None:
        raise SaveError(f"{node}: the launch files load more than one YAML into it; not guessing which to edit")
    path = pathlib.Path(config_dir) / mapping[base]
    if not path.is_file():
        raise SaveError(f"{node}: {path} does not exist (--config-dir {config_dir})")
    return path


# --- The node's current values (dynamic_reconfigure) ------------------------------------------------

def init_ros():
    """A ROS master must be up before rospy can ask anything; say so plainly instead of hanging."""
    import rosgraph
    import rospy
    if not rosgraph.is_master_online():
        raise SaveError(f"no ROS master at {rosgraph.get_master_uri()}: is the launch with the node running?")
    rospy.init_node("save_params", anonymous=True, disable_signals=True)


def live_values(node, timeout_s):
    """{parameter: value} of the node's dynamic_reconfigure server, typed as the server declares them."""
    import rospy
    from dynamic_reconfigure.client import Client
    try:
        client = Client(node, timeout=timeout_s)
    except rospy.ROSException:
        raise SaveError(f"{node}: not running, or without a dynamic_reconfigure server (no service "
                        f"{node}/set_parameters within {timeout_s:g} s; `rosnode list` shows the running "
                        f"nodes)") from None
    try:
        config = client.get_configuration(timeout=timeout_s)
    finally:
        client.close()
    if config is None:
        raise SaveError(f"{node}: its dynamic_reconfigure server sent no configuration within {timeout_s:g} s")
    return {key: value for key, value in config.items() if key != "groups"}


# --- Editing the YAML line by line ------------------------------------------------------------------

def split_value(rest):
    """`rest` is what follows a key's colon: (space before the value, the value's text, the tail: space
    and comment). A quoted value may hold '#'; a plain one ends where ' #' starts a comment."""
    text = rest.lstrip(" \t")
    lead = rest[:len(rest) - len(text)]
    if text[:1] in ("'", '"'):
        quote, i = text[0], 1
        while i < len(text):
            if text[i] == "\\" and quote == '"':
                i += 2
                continue
            if text[i] == quote:
                if quote == "'" and text[i + 1:i + 2] == "'":  # '' is an escaped quote
                    i += 2
                    continue
                return lead, text[:i + 1], text[i + 1:]
            i += 1
        return lead, text, ""
    comment = re.search(r"[ \t]#", text)
    value = (text[:comment.start()] if comment else text).rstrip(" \t")
    return lead, value, text[len(value):]


def format_float(value):
    """Readable (15 significant digits: no binary noise such as 0.30000000000000004) and still a float to
    YAML 1.1, which needs a '.' in it (1.0e-05)."""
    if math.isnan(value):
        return ".nan"
    if math.isinf(value):
        return ".inf" if value > 0 else "-.inf"
    text = "%.15g" % value
    mantissa, e, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return mantissa + e + exponent


def format_value(value, old_text):
    """The value as the file would write it: booleans true/false, integers as integers, floats readable
    (an integral float stays an integer where the file wrote one), strings quoted as the file quoted."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if value.is_integer() and re.fullmatch(r"[-+]?[0-9]+", old_text):
            return str(int(value))
        return format_float(value)
    text = str(value)
    if old_text.startswith("'"):
        return "'" + text.replace("'", "''") + "'"
    if old_text.startswith('"') or yaml.safe_load(text) != text or re.search(r"[ \t]#|:[ \t]|:$", text):
        return json.dumps(text)  # a JSON string is a valid double-quoted YAML scalar
    return text


def same_value(live, filed):
    """Unchanged? Numbers compare by value (a file's 2 equals a live 2.0), booleans only with booleans."""
    if isinstance(live, bool) or isinstance(filed, bool):
        return isinstance(live, bool) and isinstance(filed, bool) and live == filed
    if isinstance(live, (int, float)) and isinstance(filed, (int, float)):
        return math.isclose(live, filed, rel_tol=1e-12, abs_tol=0.0)
    return live == filed


def nested_parent(data, key, path=()):
    """The path of a mapping below the top level that holds `key`, or None."""
    for k, v in (data.items() if isinstance(data, dict) else ()):
        if isinstance(v, dict):
            if key in v:
                return path + (str(k),)
            found = nested_parent(v, key, path + (str(k),))
            if found:
                return found
    return None


def key_line(lines, key, path):
    """Index of the one top-level line that sets `key`; an error when there is none or several."""
    hits = [i for i, line in enumerate(lines)
            if (m := TOP_LEVEL_KEY.match(line.rstrip("\r\n"))) and m.group("key") == key]
    if len(hits) > 1:
        raise SaveError(f"{path}: key '{key}' is set on lines {', '.join(str(i + 1) for i in hits)}: "
                        f"ambiguous, not edited")
    if not hits:
        raise SaveError(f"{path}: key '{key}' is not on a plain `{key}: value` line of its own; not edited")
    return hits[0]


def edit_line(line, new_value):
    """The line with its value replaced; the comment keeps its column where the padding allows."""
    body = line.rstrip("\r\n")
    newline = line[len(body):]
    m = TOP_LEVEL_KEY.match(body)
    lead, old_text, tail = split_value(m.group("rest"))
    if not old_text or old_text.startswith(NOT_SCALAR_START):
        raise SaveError(f"key '{m.group('key')}' does not hold a one-line scalar ({old_text or 'empty'}); not edited")
    new_text = format_value(new_value, old_text)
    comment = tail.lstrip(" \t")
    if comment:
        pad = len(tail) - len(comment)
        tail = " " * max(1, pad + len(old_text) - len(new_text)) + comment
    return m.group("key") + m.group("colon") + lead + new_text + tail + newline


def write_back(text, live, path, defaults=None):
    """(new text, [changed keys], [live keys not written]). Without `defaults`: only keys in the file are
    changed. With `defaults` ({key: declared default}): the file holds exactly the live values that differ
    from their defaults (changed, added or removed). Every other line is kept byte for byte. The result is
    parsed again: it must hold the live values and every other key as before."""
    data = yaml.safe_load(text) or {}
    if not isinstance(data, dict):
        raise SaveError(f"{path}: not a YAML mapping")
    lines = text.splitlines(keepends=True)
    changed, missing, removed, added = [], [], set(), {}
    for key in sorted(live):
        wanted = defaults is None or (key in defaults and not same_value(live[key], defaults[key]))
        if key not in data:
            parent = nested_parent(data, key)
            if parent:
                raise SaveError(f"{path}: key '{key}' is nested under '{'/'.join(parent)}', but the node "
                                f"reads it at the top level (~{key}); not edited")
            if defaults is not None and key in defaults and wanted:
                added[key] = live[key]
                changed.append(key)
            elif defaults is None or key not in defaults:
                missing.append(key)
            continue
        i = key_line(lines, key, path)
        if not wanted:
            removed.add(i)
            changed.append(key)
            continue
        if same_value(live[key], data[key]):
            continue
        try:
            lines[i] = edit_line(lines[i], live[key])
        except SaveError as e:
            raise SaveError(f"{path}:{i + 1}: {e}") from None
        changed.append(key)
    lines = [line for i, line in enumerate(lines) if i not in removed]
    if added and lines and not lines[-1].endswith("\n"):
        lines[-1] += "\n"
    lines += ["%s: %s\n" % (key, format_value(value, "")) for key, value in added.items()]
    lines = with_empty_mapping_marker(lines)
    new_text = "".join(lines)
    expected = dict(data)
    for key in changed:
        if defaults is not None and key in defaults and same_value(live[key], defaults[key]):
            expected.pop(key, None)
        else:
            expected[key] = live[key]
    reread = yaml.safe_load(new_text) or {}
    if set(reread) != set(expected) or not all(same_value(expected[k], reread[k]) for k in expected):
        raise SaveError(f"{path}: the edited file would not read back as the live values; not written")
    return new_text, changed, missing


def with_empty_mapping_marker(lines):
    """`{}` stands for a file of no keys: kept (or put back) when no key is left, dropped when one is."""
    has_keys = any(TOP_LEVEL_KEY.match(line.rstrip("\r\n")) for line in lines)
    marker = [i for i, line in enumerate(lines) if EMPTY_MAPPING.match(line.rstrip("\r\n"))]
    if has_keys:
        return [line for i, line in enumerate(lines) if i not in marker]
    if not marker:
        return lines + ["{}\n"]
    return lines


def replace_file(path, text):
    """Write through a temporary file in the same folder, so an interrupted write leaves the old file."""
    path = pathlib.Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name + ".")
    try:
        with os.fdopen(fd, "w", newline="") as f:
            f.write(text)
        os.chmod(tmp, path.stat().st_mode & 0o7777)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


# --- Command line -----------------------------------------------------------------------------------

def resolve_node(name):
    import rosgraph.names
    return rosgraph.names.script_resolve_name("save_params", name)


def shown(path):
    """A path as the user would type it: relative to the working folder when it is below it."""
    relative = os.path.relpath(path)
    return path if relative.startswith("..") else relative


def save_node(node, config_dir, dry_run, timeout_s, out=sys.stdout, err=sys.stderr):
    """One node: read, compare, print the diff, write unless dry_run."""
    path = shown(yaml_path_for(node, config_dir))
    live = live_values(node, timeout_s)
    with open(path, newline="") as f:
        old = f.read()
    new, changed, missing = write_back(old, live, path, declared_defaults(path))
    if missing:
        err.write(f"{node}: live, not in {path} (not added): {', '.join(missing)}\n")
    if not changed:
        err.write(f"{node}: {path} already holds the live values\n")
        return
    out.writelines(difflib.unified_diff(old.splitlines(keepends=True), new.splitlines(keepends=True),
                                        f"{path}", f"{path} ({node} live)"))
    if dry_run:
        err.write(f"{node}: dry run, {path} not written ({len(changed)} changed: {', '.join(changed)})\n")
    else:
        replace_file(path, new)
        err.write(f"{node}: wrote {len(changed)} value(s) to {path}: {', '.join(changed)}\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("nodes", nargs="+", metavar="NODE", help="e.g. /disparity_detector /arbiter")
    ap.add_argument("--dry-run", action="store_true", help="print the diff, write nothing")
    ap.add_argument("--config-dir", default=str(CONFIG_DIR), help="folder of the YAMLs (default: %(default)s)")
    ap.add_argument("--timeout", type=float, default=3.0, help="seconds to wait for a node (default: %(default)s)")
    args = ap.parse_args(argv)
    nodes = [resolve_node(n) for n in args.nodes]
    failed = False
    try:
        for node in nodes:  # the mapping first: an unknown node needs no ROS master to be refused
            yaml_path_for(node, args.config_dir)
        init_ros()
    except SaveError as e:
        print(f"save_params: {e}", file=sys.stderr)
        return 1
    for node in nodes:
        try:
            save_node(node, args.config_dir, args.dry_run, args.timeout)
        except SaveError as e:
            print(f"save_params: {e}", file=sys.stderr)
            failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
