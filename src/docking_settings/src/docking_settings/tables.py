"""The README's parameter table of each declaration, between <!-- settings:NODE --> and
<!-- /settings:NODE --> in the README the declaration names. Written and checked by
scripts/settings_tables.py; the settings_consistency rostest fails when a table is not current."""
import pathlib
import re

import yaml

from docking_settings.declarations import flatten


def show(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(show(v) for v in value) + "]"
    return str(value)


def show_range(setting):
    if setting.choices:
        return ", ".join(setting.choices)
    if setting.range:
        return "%s .. %s" % (show(setting.range[0]), show(setting.range[1]))
    return ""


def overrides(declaration, workspace):
    """key -> [(file, value)] of the shipped files that change the default."""
    found = {}
    for name in declaration.config:
        data = flatten(yaml.safe_load((pathlib.Path(workspace) / name).read_text()) or {})
        for key, value in data.items():
            found.setdefault(key, []).append((pathlib.Path(name).name, value))
    return found


def rows(declaration, workspace, testbed):
    shipped = overrides(declaration, workspace)
    out = []
    for key, s in declaration.settings.items():
        if bool(s.testbed) != testbed:
            continue
        meaning = s.doc + ((" *Test bed: %s.*" % s.testbed) if s.testbed else "")
        shipped_text = "; ".join("%s: %s" % (f, show(v)) for f, v in shipped.get(key, []))
        out.append("| `%s`%s | %s | %s | %s | %s | %s | %s |" % (
            key, " (live)" if s.live else "", s.type.replace("_", " "), show(s.default), show_range(s),
            s.unit, shipped_text, meaning.replace("|", "\\|")))
    return out


def table(declaration, workspace):
    header = ["| Setting | Type | Default | Range | Unit | Shipped | Meaning |", "|---|---|---|---|---|---|---|"]
    lines = ["<!-- settings:%s -->" % declaration.node,
             "Generated from `%s` by `scripts/settings_tables.py` (do not edit here). (live): changeable "
             "while running (`rosrun dynamic_reconfigure dynparam`). Shipped: the value a file of `config/` "
             "sets instead of the default." % declaration.path.relative_to(workspace), ""]
    lines += header + rows(declaration, workspace, testbed=False)
    test_bed = rows(declaration, workspace, testbed=True)
    if test_bed:
        lines += ["", "Test-bed settings: they hold for our floor test bed or our simulator; revisit them on "
                  "another rig.", ""] + header + test_bed
    lines.append("<!-- /settings:%s -->" % declaration.node)
    return "\n".join(lines)


def block_pattern(node):
    return re.compile(r"<!-- settings:%s -->.*?<!-- /settings:%s -->" % (re.escape(node), re.escape(node)), re.S)


def current_block(declaration, workspace):
    """The table now in the README, or None when the README has no markers for this node."""
    readme = pathlib.Path(workspace) / declaration.readme
    match = block_pattern(declaration.node).search(readme.read_text())
    return match.group(0) if match else None


def write(declaration, workspace):
    readme = pathlib.Path(workspace) / declaration.readme
    text = readme.read_text()
    new = table(declaration, workspace)
    pattern = block_pattern(declaration.node)
    if not pattern.search(text):
        raise ValueError("%s has no <!-- settings:%s --> ... <!-- /settings:%s --> block" %
                         (declaration.readme, declaration.node, declaration.node))
    readme.write_text(pattern.sub(lambda _: new, text))
