"""What must hold between a declaration, the shipped YAML files and the README (settings_consistency
rostest): each file's keys are declared, of the declared type and allowed; no file restates a default (two
homes of one value drift); the README's table is the one the declaration makes."""
import pathlib

import yaml

from docking_settings.declarations import flatten
from docking_settings import tables


def problems(declaration, workspace):
    found = []
    if declaration.defaults_from:
        data = flatten(yaml.safe_load((pathlib.Path(workspace) / declaration.defaults_from).read_text()) or {})
        for key in sorted(set(data) - set(declaration.settings)):
            found.append("%s: %s: no setting of %s reads it" % (declaration.defaults_from, key, declaration.node))
    for name in declaration.config:
        path = pathlib.Path(workspace) / name
        data = flatten(yaml.safe_load(path.read_text()) or {})
        for key, value in data.items():
            setting = declaration.settings.get(key)
            if setting is None:
                found.append("%s: %s: no setting of %s reads it" % (name, key, declaration.node))
                continue
            problem = setting.problem(value)
            if problem:
                found.append("%s: %s: %s" % (name, key, problem))
            elif value == setting.default and type(value) == type(setting.default):
                found.append("%s: %s: restates the declared default %r (remove it, or change the default in %s)"
                             % (name, key, value, declaration.path.name))
    if declaration.readme:
        current = tables.current_block(declaration, workspace)
        if current is None:
            found.append("%s: no settings table for %s" % (declaration.readme, declaration.node))
        elif current != tables.table(declaration, workspace):
            found.append("%s: the settings table of %s is not current (scripts/settings_tables.py --write)"
                         % (declaration.readme, declaration.node))
    return found
