"""Reading and checking a settings declaration (a package's settings/<node>.yaml).

A declaration names, for one node, every setting once: its key, type, default, range, unit and one line
of meaning, whether it can change while running (dynamic_reconfigure), and whether it holds only for our
test bed. From it come the C++ structs the node's core receives (generate_settings.py), the loader and
validator (docking_settings/ros_loader.h, yaml_loader.h), dynamic_reconfigure's parameters
(reconfigure.add_live_settings), and the README's table (tables.py). See the package README.

    cpp: {header: pkg/node_settings.h, namespace: pkg::sub}
    imports: [src/pkg/settings/common.yaml]   # structs declared in another declaration (its header is included;
                                       # one without node/root only declares structs for others)
    node: arbiter                      # the node (for the README heading)
    config: [config/arbiter.yaml]      # the shipped files that set them (overrides of the defaults only)
    defaults_from: config/omni_base.yaml   # instead of `default:` per setting: a file that describes
                                       # hardware (a base, a simulator) holds every value, and is their home
    readme: src/pkg/README.md          # its table goes between <!-- settings:NAME --> and <!-- /settings -->
    root: ArbiterSettings              # the struct a node loads
    structs:
      ArbiterSettings:
        doc: one line
        settings:
          switch_range_m: {type: double, default: 2.0, range: [0.5, 10.0], unit: m, live: true, doc: "..."}
          consistency: {struct: ConsistencySettings, prefix: consistency_}     # a nested struct
"""
import pathlib
import re

import yaml

TYPES = ("double", "int", "bool", "string", "double_list", "int_list", "string_list")
SETTING_KEYS = {"type", "default", "range", "size", "choices", "unit", "doc", "live", "testbed", "paper"}
MEMBER_KEYS = {"struct", "prefix", "doc"}
IDENTIFIER = re.compile(r"^[a-z][a-z0-9_]*$")


class DeclarationError(ValueError):
    pass


class Setting:
    """One setting: `key` as it appears in YAML (prefixes of the nested structs included)."""

    def __init__(self, struct, name, spec, where, default_of=None):
        unknown = set(spec) - SETTING_KEYS
        if unknown:
            raise DeclarationError("%s: unknown fields %s" % (where, sorted(unknown)))
        self.struct, self.name, self.where = struct, name, where
        self.type = spec.get("type")
        if self.type not in TYPES:
            raise DeclarationError("%s: type must be one of %s" % (where, ", ".join(TYPES)))
        if "default" in spec and default_of is not None:
            raise DeclarationError("%s: a default here and in defaults_from: one home only" % where)
        if "default" not in spec and default_of is None:
            raise DeclarationError("%s: no default" % where)
        self.default = spec["default"] if default_of is None else default_of
        self.range = spec.get("range")
        self.size = spec.get("size", 0)
        self.choices = spec.get("choices")
        self.unit = spec.get("unit", "")
        self.doc = spec.get("doc", "")
        self.live = bool(spec.get("live", False))
        self.testbed = spec.get("testbed", "")
        self.paper = bool(spec.get("paper", False))
        if not self.doc:
            raise DeclarationError("%s: no doc (one line of meaning)" % where)
        if self.range is not None and not (len(self.range) == 2 and all(
                isinstance(b, (int, float)) and not isinstance(b, bool) for b in self.range)):
            raise DeclarationError("%s: range must be two numbers (YAML reads 1.0e6 as text: write 1.0e+6)" % where)
        self.check(self.default, "the default")

    @property
    def is_list(self):
        return self.type.endswith("_list")

    @property
    def element_type(self):
        return self.type[:-5] if self.is_list else self.type

    def problem(self, value):
        """Why `value` is not allowed for this setting, or None."""
        values = value if self.is_list else [value]
        if self.is_list:
            if not isinstance(value, list):
                return "expected a list, got %r" % (value,)
            if self.size and len(value) != self.size:
                return "expected %d entries, got %d" % (self.size, len(value))
        for v in values:
            kind = self.element_type
            if kind == "bool" and not isinstance(v, bool):
                return "expected true or false, got %r" % (v,)
            if kind == "int" and (isinstance(v, bool) or not isinstance(v, int)):
                return "expected an integer, got %r" % (v,)
            if kind == "double" and (isinstance(v, bool) or not isinstance(v, (int, float))):
                return "expected a number, got %r" % (v,)
            if kind == "string" and not (isinstance(v, str) or (isinstance(v, int) and not isinstance(v, bool))):
                return "expected a string (or an integer, taken as its text), got %r" % (v,)
            if self.range and kind in ("int", "double") and not (self.range[0] <= v <= self.range[1]):
                return "%r is outside [%r, %r]" % (v, self.range[0], self.range[1])
            if self.choices and v not in self.choices:
                return "%r is not one of %s" % (v, ", ".join(self.choices))
        return None

    def check(self, value, what):
        problem = self.problem(value)
        if problem:
            raise DeclarationError("%s: %s: %s" % (self.where, what, problem))


class Member:
    """A nested struct inside a struct: its settings' keys get `prefix`."""

    def __init__(self, name, spec, where):
        unknown = set(spec) - MEMBER_KEYS
        if unknown:
            raise DeclarationError("%s: unknown fields %s" % (where, sorted(unknown)))
        self.name, self.struct, self.prefix, self.doc = name, spec["struct"], spec.get("prefix", ""), spec.get("doc", "")


class Struct:
    def __init__(self, name, spec, where):
        self.name, self.doc = name, spec.get("doc", "")
        self.fields = []  # Setting or Member, in declaration order
        self.specs = {}   # field -> its spec, for settings made once their keys are known
        for field, field_spec in (spec.get("settings") or {}).items():
            here = "%s: %s.%s" % (where, name, field)
            if not IDENTIFIER.match(field):
                raise DeclarationError("%s: a field name is lower_case_with_underscores" % here)
            if "struct" in field_spec:
                self.fields.append(Member(field, field_spec, here))
            else:
                self.fields.append(field)
                self.specs[field] = (field_spec, here)


class Declaration:
    def __init__(self, path):
        self.path = pathlib.Path(path)
        spec = yaml.safe_load(self.path.read_text())
        where = str(self.path)
        for required in ("cpp", "structs"):
            if required not in spec:
                raise DeclarationError("%s: no '%s'" % (where, required))
        if ("node" in spec) != ("root" in spec):
            raise DeclarationError("%s: a node's declaration has both 'node' and 'root'; a struct library neither" % where)
        self.header = spec["cpp"]["header"]
        self.namespace = spec["cpp"]["namespace"]
        self.node = spec.get("node")
        self.config = list(spec.get("config") or [])
        self.readme = spec.get("readme")
        self.root = spec.get("root")
        self.doc = spec.get("doc", "")
        self.workspace = self.path.resolve().parents[3]  # src/<package>/settings/<node>.yaml
        self.imports = [Declaration(self.workspace / i) for i in spec.get("imports") or []]
        for imported in self.imports:
            if imported.namespace != spec["cpp"]["namespace"]:
                raise DeclarationError("%s: imports %s of another namespace" % (where, imported.path))
        self.defaults_from = spec.get("defaults_from")
        self.default_values = None
        if self.defaults_from:
            self.default_values = flatten(yaml.safe_load((self.workspace / self.defaults_from).read_text()) or {})
        self.structs = {name: Struct(name, s, where) for name, s in spec["structs"].items()}
        self.imported_structs = {}
        for imported in self.imports:
            self.imported_structs.update(imported.structs)
            self.imported_structs.update(imported.imported_structs)
        clash = set(self.structs) & set(self.imported_structs)
        if clash:
            raise DeclarationError("%s: %s declared here and imported" % (where, sorted(clash)))
        self.settings = {}  # key -> Setting, every setting reachable from the root
        if self.root is None:
            self._resolve_library()
        else:
            if self.root not in self.structs:
                raise DeclarationError("%s: root %s is not declared" % (where, self.root))
            self._collect(self.root, "", [])
        for key, setting in self.settings.items():
            if setting.live and "/" in key:
                raise DeclarationError("%s: %s: a live setting's key cannot hold '/'" % (where, key))

    def _resolve_library(self):
        """A struct library's settings, each with the default its spec gives (no keys: no node reads it as such)."""
        if self.defaults_from:
            raise DeclarationError("%s: a struct library declares its defaults (no defaults_from)" % self.path)
        for name, struct in self.structs.items():
            for index, field in enumerate(struct.fields):
                if isinstance(field, str):
                    field_spec, here = struct.specs[field]
                    struct.fields[index] = Setting(name, field, field_spec, here)

    def _collect(self, struct_name, prefix, path):
        if struct_name in path:
            raise DeclarationError("%s: %s contains itself" % (self.path, struct_name))
        struct = self.structs.get(struct_name) or self.imported_structs.get(struct_name)
        if struct is None:
            raise DeclarationError("%s: struct %s is not declared" % (self.path, struct_name))
        for index, field in enumerate(struct.fields):
            if isinstance(field, Member):
                self._collect(field.struct, prefix + field.prefix, path + [struct_name])
                continue
            if struct_name in self.imported_structs and isinstance(field, str):
                raise DeclarationError("%s: imported struct %s is not resolved" % (self.path, struct_name))
            if isinstance(field, Setting) and self.default_values is not None:
                raise DeclarationError("%s: %s is used twice: its defaults cannot come from one file (defaults_from)"
                                       % (self.path, struct_name))
            if isinstance(field, str):  # made here, where its key (and so its default's place) is known
                field_spec, here = struct.specs[field]
                key = prefix + field
                default = None
                if self.default_values is not None:
                    if key not in self.default_values:
                        raise DeclarationError("%s: %s: not in %s (defaults_from)" % (here, key, self.defaults_from))
                    default = self.default_values[key]
                field = Setting(struct_name, field, field_spec, here, default)
                struct.fields[index] = field
            key = prefix + field.name
            if key in self.settings:
                raise DeclarationError("%s: key %s is declared twice" % (self.path, key))
            self.settings[key] = field

    def ordered_structs(self):
        """Structs in an order where each comes after the structs it contains."""
        done, order = set(), []

        def visit(name):
            if name in done or name not in self.structs:  # imported structs come with their own header
                return
            for field in self.structs[name].fields:
                if isinstance(field, Member):
                    visit(field.struct)
            done.add(name)
            order.append(name)

        for name in self.structs:
            visit(name)
        return order


def find_declarations(workspace):
    """Every node's settings declaration of the workspace's packages (struct libraries left out)."""
    declarations = [Declaration(p) for p in sorted(pathlib.Path(workspace).glob("src/*/settings/*.yaml"))]
    return [d for d in declarations if d.node is not None]


def flatten(mapping, prefix=""):
    """A loaded YAML file's keys as the loader reads them: nested dictionaries joined with '/'."""
    out = {}
    for key, value in (mapping or {}).items():
        if isinstance(value, dict):
            out.update(flatten(value, prefix + key + "/"))
        else:
            out[prefix + key] = value
    return out


def declared_defaults(config_file):
    """{key: declared default} of the node whose declaration claims a config file of this name (the shipped
    one or a copy; keyed as the loader reads them); None when no declaration claims it."""
    name = pathlib.Path(config_file).name
    workspace = pathlib.Path(__file__).resolve().parents[4]
    for declaration in find_declarations(workspace):
        if name in {pathlib.Path(c).name for c in declaration.config}:
            return {key: setting.default for key, setting in declaration.settings.items()}
    return None


def effective_values(config_file):
    """What a node reads from a config file: its declaration's defaults with the file's overrides on top, keyed
    as the loader reads them. For a script that needs one value of a node's settings (e.g. a camera's rate_hz)
    from a configuration folder. A file no declaration claims is read as it is."""
    values = dict(declared_defaults(config_file) or {})
    values.update(flatten(yaml.safe_load(pathlib.Path(config_file).read_text()) or {}))
    return values
