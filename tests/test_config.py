from dataclasses import dataclass, field

import pytest

from datagen.config import load_config
from datagen.errors import ConfigError


@dataclass(frozen=True, kw_only=True)
class Inner:
    thickness: float = field(default=0.003, metadata={"min": 0.0, "max": 0.05})


@dataclass(frozen=True, kw_only=True)
class Example:
    iterations: int = field(default=10, metadata={"min": 1, "max": 100})
    rest_pose: str = field(default="t-pose", metadata={"choices": ("t-pose", "a-pose")})
    enabled: bool = True
    sizes: tuple[float, float] = (1.0, 2.0)
    inner: Inner = field(default_factory=Inner)


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_toml_and_yaml_load_the_same(tmp_path):
    a = load_config(Example, write(tmp_path, "a.toml", "iterations = 5\nrest_pose = 'a-pose'\n[inner]\nthickness = 0.01\n"))
    b = load_config(Example, write(tmp_path, "b.yaml", "iterations: 5\nrest_pose: a-pose\ninner:\n  thickness: 0.01\n"))
    assert a == b == Example(iterations=5, rest_pose="a-pose", inner=Inner(thickness=0.01))


def test_yaml_reads_exponents_without_a_dot_as_numbers(tmp_path):
    """``3e-4`` is a number in TOML and YAML 1.2; PyYAML (YAML 1.1) made it the string '3e-4',
    which the strict loader then refused. Strings that only look like it stay strings."""
    from datagen.config import read_config_file

    a = load_config(Example, write(tmp_path, "a.yaml", "inner:\n  thickness: 3e-3\nsizes: [1e-1, 2.5E+0]\n"))
    b = load_config(Example, write(tmp_path, "b.toml", "sizes = [1e-1, 2.5E+0]\n[inner]\nthickness = 3e-3\n"))
    assert a == b == Example(inner=Inner(thickness=0.003), sizes=(0.1, 2.5))
    raw = read_config_file(write(tmp_path, "c.yaml", "x: -1e3\ny: '3e-4'\nz: tshirt:0\nw: 1.5e-2\nv: 7\n"))
    assert raw == {"x": -1000.0, "y": "3e-4", "z": "tshirt:0", "w": 0.015, "v": 7}


def test_unknown_key_names_key_file_and_allowed(tmp_path):
    p = write(tmp_path, "c.toml", "iteration = 5\n")
    with pytest.raises(ConfigError) as e:
        load_config(Example, p)
    msg = str(e.value)
    assert "iteration" in msg and str(p) in msg and "iterations" in msg and "rest_pose" in msg


def test_nested_unknown_key_is_dotted(tmp_path):
    with pytest.raises(ConfigError, match=r"inner\.thick"):
        load_config(Example, write(tmp_path, "c.toml", "[inner]\nthick = 1.0\n"))


@pytest.mark.parametrize(
    "text, pattern",
    [
        ("iterations = 'ten'", r"iterations must be an integer"),
        ("iterations = 1.5", r"iterations must be an integer"),
        ("iterations = 0", r"iterations = 0 is out of range; allowed: 1 <= iterations <= 100"),
        ("rest_pose = 'x-pose'", r"rest_pose = 'x-pose' is not allowed; choose one of \['t-pose', 'a-pose'\]"),
        ("enabled = 1", r"enabled must be true or false"),
        ("sizes = 3", r"sizes must be a list"),
        ("[inner]\nthickness = 0.5", r"inner.thickness = 0.5 is out of range"),
    ],
)
def test_wrong_types_and_ranges(tmp_path, text, pattern):
    p = write(tmp_path, "d.toml", text + "\n")
    with pytest.raises(ConfigError, match=pattern) as e:
        load_config(Example, p)
    assert str(p) in str(e.value)


def test_bad_files(tmp_path):
    with pytest.raises(ConfigError, match="does not exist"):
        load_config(Example, tmp_path / "missing.toml")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(Example, write(tmp_path, "e.toml", "iterations = = 3"))
    with pytest.raises(ConfigError, match="use .toml, .yaml, .yml or .json"):
        load_config(Example, write(tmp_path, "e.ini", "{}"))
    with pytest.raises(ConfigError, match="not valid JSON"):  # read by the YAML parser, named as what it is
        load_config(Example, write(tmp_path, "e.json", "{"))


def test_section(tmp_path):
    p = write(tmp_path, "f.toml", "[solver]\niterations = 7\n")
    assert load_config(Example, p, section="solver").iterations == 7
    with pytest.raises(ConfigError, match=r"missing section \[body\]"):
        load_config(Example, p, section="body")


def test_command_line_assignments_are_read_as_toml_values_and_checked_by_the_loader():
    from datagen.config import load_config, parse_assignments
    from datagen.sim.solver import SolverConfig

    kw = parse_assignments(["iterations=10", "chebyshev_rho=0.5", "self_collision=false", "global_friction=lagged",
                            "gravity=[0.0, -9.81, 0.0]"])
    assert kw == {"iterations": 10, "chebyshev_rho": 0.5, "self_collision": False, "global_friction": "lagged",
                  "gravity": [0.0, -9.81, 0.0]}
    assert load_config(SolverConfig, kw).iterations == 10
    with pytest.raises(ConfigError, match="expected KEY=VALUE"):
        parse_assignments(["iterations"])
    with pytest.raises(ConfigError, match="iterations"):
        load_config(SolverConfig, parse_assignments(["iterations=ten"]))
    with pytest.raises(ConfigError, match="no_such_field"):
        load_config(SolverConfig, parse_assignments(["no_such_field=1"]))
