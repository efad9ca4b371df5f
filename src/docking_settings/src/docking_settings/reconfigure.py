"""dynamic_reconfigure's parameters from a settings declaration: a package's .cfg calls

    from docking_settings.reconfigure import add_live_settings
    add_live_settings(gen, "<the declaration>.yaml")

and gets every setting declared `live: true`, with its declared default, range, choices and meaning."""
from dynamic_reconfigure.parameter_generator_catkin import bool_t, double_t, int_t, str_t

from docking_settings.declarations import Declaration

KINDS = {"double": double_t, "int": int_t, "bool": bool_t, "string": str_t}


def add_live_settings(gen, declaration_path):
    declaration = Declaration(declaration_path)
    for key, setting in declaration.settings.items():
        if not setting.live:
            continue
        kind = KINDS.get(setting.type)
        if kind is None:
            raise ValueError("%s: %s: a list cannot be live" % (declaration_path, key))
        doc = (setting.doc + (" [%s]" % setting.unit if setting.unit else ""))[:250]
        extra = {}
        if setting.choices:
            extra["edit_method"] = gen.enum([gen.const(c, str_t, c, c) for c in setting.choices], key)
        if setting.range and setting.type in ("double", "int"):
            gen.add(key, kind, 0, doc, setting.default, setting.range[0], setting.range[1], **extra)
        else:
            gen.add(key, kind, 0, doc, setting.default, **extra)
    return declaration
