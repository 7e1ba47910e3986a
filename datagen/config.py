"""One strict loader for configuration files (TOML or YAML) into frozen keyword-only dataclasses.

Each component declares its configuration as ``@dataclass(frozen=True, kw_only=True)`` next to
itself. Range and choice limits go in the field's metadata::

    iterations: int = field(default=10, metadata={"min": 1, "max": 1000})
    rest_pose: str = field(default="t-pose", metadata={"choices": ("t-pose", "a-pose")})

:func:`load_config` rejects unknown keys, wrong types and values outside those limits with a
:class:`~datagen.errors.ConfigError` that names the key, the file and what is allowed.

A nested dataclass is a nested table; a dotted key (``self_contact.radius = 0.004``, as ``--set``
gives it) is read into its table too. A class whose keys moved into nested tables keeps its old keys
readable with a ``config_aliases`` class attribute: old key -> its dotted place.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import tomllib
import types
import typing
from pathlib import Path
from typing import Any, TypeVar

from datagen.errors import ConfigError

T = TypeVar("T")


def read_config_file(path: str | Path) -> dict[str, Any]:
    """Read a ``.toml``, ``.yaml``/``.yml`` or ``.json`` file into a dict; errors name the file."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"config file {path} does not exist; give the path of a .toml, .yaml or .json file")
    suffix = path.suffix.lower()
    try:
        if suffix == ".toml":
            with path.open("rb") as fh:
                data = tomllib.load(fh)
        elif suffix in (".yaml", ".yml", ".json"):  # JSON is YAML (drape info --config prints JSON)
            import yaml

            with path.open("r", encoding="utf-8") as fh:
                data = yaml.load(fh, Loader=_yaml_loader())  # noqa: S506 (a SafeLoader)
        else:
            raise ConfigError(f"config file {path} has suffix '{suffix}'; use .toml, .yaml, .yml or .json")
    except UnicodeDecodeError as exc:  # any of the three: each is UTF-8 text
        raise ConfigError(f"config file {path} is not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at offset "
                          f"{exc.start} is not UTF-8): save it as UTF-8 (a {suffix} config is UTF-8 text)") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config file {path} is not valid TOML: {' '.join(str(exc).split())}") from exc
    except Exception as exc:  # yaml.YAMLError without importing yaml at module level
        if type(exc).__module__.startswith("yaml"):
            kind = "JSON" if suffix == ".json" else "YAML"
            raise ConfigError(f"config file {path} is not valid {kind}: {' '.join(str(exc).split())}") from exc
        raise
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"config file {path} must hold a table/mapping at the top level, not {type(data).__name__}")
    return data


@functools.cache
def _yaml_loader():
    """PyYAML's SafeLoader that also reads ``3e-4`` and ``1e3`` as numbers, as YAML 1.2 and TOML
    do (YAML 1.1 wants a dot in a float, so ``lr: 3e-4`` was the string '3e-4'), and refuses a
    key given twice in one mapping, as TOML does (PyYAML keeps the last one without a word)."""
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        def construct_mapping(self, node, deep=False):
            if isinstance(node, yaml.MappingNode):
                seen: dict = {}
                for key_node, _ in node.value:
                    if key_node.tag == "tag:yaml.org,2002:merge":
                        continue  # `<<: *anchor` merges are meant to be overridden
                    key = self.construct_object(key_node, deep=True)
                    try:
                        first = seen.get(key)
                    except TypeError:  # an unhashable key: SafeLoader says so itself
                        continue
                    if first is not None:
                        raise yaml.constructor.ConstructorError(
                            "while reading a mapping", node.start_mark,
                            f"found the key {key!r} twice (first on line {first}); give each key once",
                            key_node.start_mark)
                    seen[key] = key_node.start_mark.line + 1
            return super().construct_mapping(node, deep=deep)

    Loader.add_implicit_resolver("tag:yaml.org,2002:float", re.compile(
        r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"), list("-+0123456789"))
    return Loader


def parse_assignments(items: typing.Iterable[str], option: str = "--set") -> dict[str, Any]:
    """A command line's repeated ``KEY=VALUE`` items as a mapping for :func:`load_config`: each
    VALUE read as a TOML value (``10``, ``0.5``, ``true``, ``[0.0, -9.81, 0.0]``), or kept as text
    where it is none (``lagged``). The loader then checks keys, types and limits."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"{option} {item!r}: expected KEY=VALUE")
        try:
            out[key.strip()] = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            out[key.strip()] = text
    return out


def load_config(cls: type[T], source: str | Path | dict[str, Any], *, section: str | None = None) -> T:
    """Build the frozen dataclass ``cls`` from a file or dict, strictly.

    Args:
        cls: a frozen, keyword-only dataclass type.
        source: a path to a TOML/YAML file, or an already-parsed mapping.
        section: optional top-level key whose table configures ``cls``.
    """
    where = str(source) if not isinstance(source, dict) else "<mapping>"
    data = read_config_file(source) if not isinstance(source, dict) else source
    if section is not None:
        if section not in data:
            raise ConfigError(f"{where}: missing section [{section}]")
        data = data[section]
        prefix = section
    else:
        prefix = ""
    return _build(cls, data, where, prefix)


def _build(cls: type[T], data: Any, where: str, prefix: str) -> T:
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f"{cls!r} is not a dataclass")
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: '{prefix or cls.__name__}' must be a table/mapping, got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    data = _nested(cls, data, fields, where, prefix)
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(
            f"{where}: unknown key(s) {', '.join(_dotted(prefix, k) for k in unknown)}; "
            f"allowed keys are: {', '.join(sorted(fields))}"
        )
    kwargs = {}
    for name, value in data.items():
        f = fields[name]
        key = _dotted(prefix, name)
        kwargs[name] = _check_value(hints[name], value, f.metadata, where, key)
    missing = [
        n for n, f in fields.items()
        if n not in kwargs and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    ]
    if missing:
        raise ConfigError(f"{where}: missing required key(s) {', '.join(_dotted(prefix, m) for m in missing)}")
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:  # InputError is a ValueError: a component's own check
        raise ConfigError(f"{where}: {prefix + ': ' if prefix else ''}{exc}") from exc


def _nested(cls: type, data: dict, fields: dict, where: str, prefix: str) -> dict:
    """``data`` with every dotted key (``group.key``) and every key ``cls.config_aliases`` renames to
    one moved into its group's table (a key given twice, in the table and outside it, is refused)."""
    aliases = getattr(cls, "config_aliases", None) or {}
    out, moved = {}, {}
    for key, value in data.items():
        head, dot, rest = aliases.get(key, key).partition(".")
        if dot and head in fields:
            moved.setdefault(head, []).append((key, rest, value))
        else:
            out[key] = value
    for head, items in moved.items():
        table = out.get(head, {})
        if not isinstance(table, dict):
            raise ConfigError(f"{where}: '{_dotted(prefix, head)}' must be a table/mapping, got {type(table).__name__}")
        table = dict(table)
        for key, rest, value in items:
            if rest in table:
                raise ConfigError(f"{where}: {_dotted(prefix, key)} and {_dotted(prefix, f'{head}.{rest}')} are the "
                                  "same setting; give it once")
            table[rest] = value
        out[head] = table
    return out


def _dotted(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp))


def _check_value(tp: Any, value: Any, meta: Any, where: str, key: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for option in (a for a in args if a is not type(None)):
            try:
                return _check_value(option, value, meta, where, key)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(errors[-1] if errors else f"{where}: {key} has an invalid value {value!r}")
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(f"{where}: {key} = {value!r} is not allowed; choose one of {list(args)}")
        return value
    if dataclasses.is_dataclass(tp):
        return _build(tp, value, where, key)
    if origin in (tuple, list):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"{where}: {key} must be a list, got {type(value).__name__} {value!r}")
        item_tp = args[0] if args else Any
        items = [
            _check_value(item_tp, v, {}, where, f"{key}[{i}]") if item_tp is not Any else v
            for i, v in enumerate(value)
        ]
        if "choices" in meta:
            bad = [v for v in items if v not in meta["choices"]]
            if bad:
                raise ConfigError(f"{where}: {key} has {bad!r}; allowed values are {list(meta['choices'])}")
        return tuple(items) if origin is tuple else items
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: {key} must be true or false, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{where}: {key} must be an integer, got {type(value).__name__} {value!r}")
    elif tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{where}: {key} must be a number, got {type(value).__name__} {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"{where}: {key} must be finite, got {value!r}")
    elif tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where}: {key} must be a string, got {type(value).__name__} {value!r}")
    elif tp is not Any:
        raise ConfigError(f"{where}: {key} has unsupported type {_type_name(tp)}")
    lo, hi = meta.get("min"), meta.get("max")
    if lo is not None and value < lo or hi is not None and value > hi:
        raise ConfigError(
            f"{where}: {key} = {value!r} is out of range; allowed: "
            f"{lo if lo is not None else '-inf'} <= {key} <= {hi if hi is not None else 'inf'}"
        )
    if "choices" in meta and value not in meta["choices"]:
        raise ConfigError(f"{where}: {key} = {value!r} is not allowed; choose one of {list(meta['choices'])}")
    return value
