"""drake_sim.base.config: one typed error naming the file and the key for every malformed file."""

import dataclasses as dc

import pytest

import drake_sim.base.config as mut
from drake_sim.base.errors import ConfigError


@dc.dataclass
class Inner:
    gain: float = 1.0
    names: list[str] = dc.field(default_factory=list)


@dc.dataclass
class Schema:
    count: int = 3
    rate: float = 0.5
    enabled: bool = True
    label: str = "a"
    inner: Inner = dc.field(default_factory=Inner)
    table: dict[str, list[float]] = dc.field(default_factory=dict)
    maybe: Inner | None = None


def test_missing_keys_keep_defaults_and_values_load():
    dut = mut.load_typed(Schema, data="rate: 2.5\ninner: {names: [x, y]}\n")
    assert dut == Schema(rate=2.5, inner=Inner(names=["x", "y"]))
    assert mut.load_typed(Schema, data="") == Schema()
    assert mut.load_typed(Schema, data="rate: 1e6").rate == 1e6  # YAML 1.1 reads it as text


def test_defaults_are_kept_under_the_file():
    base = Schema(count=7)
    assert mut.load_typed(Schema, data="rate: 1.0", defaults=base).count == 7


@pytest.mark.parametrize(
    "text, match",
    [
        ("bogus: 1", "unknown key 'bogus'"),
        ("inner: {gian: 2}", "unknown key 'inner.gian'"),
        ("rate: abc", "'rate' must be a number"),
        ("rate: .nan", "'rate' must be finite"),
        ("rate: .inf", "'rate' must be finite"),
        ("count: 1.5", "'count' must be an integer"),
        ("enabled: 3", "'enabled' must be true or false"),
        ("label: [1]", "'label' must be a string"),
        ("rate: true", "'rate' must be a number"),
        ("inner: 5", "'inner' must be a mapping"),
        ("inner: {names: 3}", "'inner.names' must be a list"),
        ("table: {a: [1, x]}", r"'table.a\[1\]' must be a number"),
        ("maybe: {gain: .nan}", "'maybe.gain' must be finite"),
        ("rate: [", "malformed YAML at line"),
        ("- 1", "expected a mapping"),
    ],
)
def test_malformed_text_names_the_key(text, match):
    with pytest.raises(ConfigError, match=match) as info:
        mut.load_typed(Schema, data=text, where="f.yaml")
    assert str(info.value).startswith("f.yaml: ")


def test_null_for_an_optional_section():
    assert mut.load_typed(Schema, data="maybe: null").maybe is None
    assert mut.load_typed(Schema, data="maybe: {gain: 2}").maybe == Inner(gain=2.0)


def test_files_missing_directory_binary_and_unreadable(tmp_path):
    with pytest.raises(ConfigError, match="no such file"):
        mut.load_typed(Schema, filename=tmp_path / "nope.yaml")
    with pytest.raises(ConfigError, match="is a directory"):
        mut.load_typed(Schema, filename=tmp_path)
    binary = tmp_path / "latin1.yaml"
    binary.write_bytes("label: caf\xe9\n".encode("latin-1"))
    with pytest.raises(ConfigError, match=r"latin1.yaml: not UTF-8 text \(byte 10\)"):
        mut.load_typed(Schema, filename=binary)
    good = tmp_path / "good.yaml"
    good.write_text("label: café\n", encoding="utf-8")
    assert mut.load_typed(Schema, filename=good).label == "café"


def test_exactly_one_source():
    with pytest.raises(TypeError):
        mut.load_typed(Schema)
    with pytest.raises(TypeError):
        mut.load_typed(Schema, filename="a.yaml", data="rate: 1")


def test_overrides_apply_in_order_and_name_the_item():
    dut = mut.apply_overrides(Schema, Schema(), ["inner.gain=4", "rate=0.25", "rate=0.75"])
    assert dut.inner.gain == 4.0 and dut.rate == 0.75
    for bad, match in [
        ("inner.gian=1", "unknown key 'inner.gian'"),
        ("rate", "expected KEY=VALUE"),
        ("inner..gain=1", "expected KEY=VALUE"),
        ("rate=.nan", "must be finite"),
    ]:
        with pytest.raises(ConfigError, match=match) as info:
            mut.apply_overrides(Schema, Schema(), [bad])
        assert f"--set {bad!r}" in str(info.value)


def test_check_tree_passes_unknown_schemas_through():
    """A type that is neither a dataclass nor a Drake struct is left to Drake's loader."""
    mut.check_tree(object, {"anything": 1}, "f.yaml")


def test_load_checked_reads_types_and_checks_the_file(tmp_path):
    path = tmp_path / "thing.yaml"
    path.write_text("rate: 2.5\n")
    seen = []

    def check(value, where):
        seen.append(where)
        if value.rate > 10:
            raise ConfigError(f"{where}: 'rate' is too large")
        return value

    assert mut.load_checked(Schema, path, check) == Schema(rate=2.5)
    assert seen == [str(path)]
    assert mut.load_checked(Schema, path, check, defaults=Schema(count=7)).count == 7
    path.write_text("rate: 20.0\n")
    with pytest.raises(ConfigError, match="thing.yaml: 'rate' is too large"):
        mut.load_checked(Schema, path, check)
    with pytest.raises(ConfigError, match="thing file"):
        mut.load_checked(Schema, tmp_path / "none.yaml", check, what="thing file")
    path.write_text("colour: red\n")
    with pytest.raises(ConfigError, match="colour"):
        mut.load_checked(Schema, path, check)
