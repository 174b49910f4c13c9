"""drake_sim.base.config: one typed error naming the file and the key for every malformed file."""

import dataclasses as dc
import subprocess
import sys

import pytest
import yaml

import drake_sim.base.config as mut
from drake_sim.base.errors import ConfigError


@dc.dataclass
class Inner:
    gain: float = 1.0
    names: list[str] = dc.field(default_factory=list)


@dc.dataclass
class Push:
    time: float = 0.0  # s
    force: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 0.0])  # N


@dc.dataclass
class Schema:
    count: int = 3
    rate: float = 0.5
    enabled: bool = True
    label: str = "a"
    inner: Inner = dc.field(default_factory=Inner)
    table: dict[str, list[float]] = dc.field(default_factory=dict)
    maybe: Inner | None = None
    position: list[float] = dc.field(default_factory=lambda: [1.0, 2.0, 3.0])
    grid: list[list[float]] = dc.field(default_factory=lambda: [[1.0, 2.0], [3.0, 4.0]])
    pushes: list[Push] = dc.field(default_factory=lambda: [Push(), Push(time=2.0)])


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
        ("=1", "expected KEY=VALUE"),
        ("inner..gain=1", "malformed key 'inner..gain': an empty name"),
        ("rate=.nan", "must be finite"),
    ]:
        with pytest.raises(ConfigError, match=match) as info:
            mut.apply_overrides(Schema, Schema(), [bad])
        assert f"--set {bad!r}" in str(info.value)


@pytest.mark.parametrize(
    "key, steps",
    [
        ("rate", ("rate",)),
        ("a.b[2].c", ("a", "b", 2, "c")),
        ("m[1][0]", ("m", 1, 0)),
        ("scene.object.position[0]", ("scene", "object", "position", 0)),
        (" a . b [ 3 ] ", ("a", "b", 3)),
    ],
)
def test_parse_key_path(key, steps):
    assert mut.parse_key_path(key) == steps
    assert mut.format_key_path(steps) == "".join(key.split())


@pytest.mark.parametrize(
    "key, match",
    [
        ("a..b", "an empty name"),
        ("", "an empty name"),
        ("a.", "an empty name"),
        ("[0]", "no name before '\\[0\\]'"),
        ("a.[0]", "no name before"),
        ("a[", "brackets out of place in 'a\\['"),
        ("a]", "brackets out of place"),
        ("a[0]b", "brackets out of place"),
        ("a[[0]]", "brackets out of place"),
        ("a[]", "index \\[\\] is not a whole number"),
        ("a[x]", "index \\[x\\] is not a whole number"),
        ("a[1.5]", "brackets out of place|not a whole number"),
        ("a[-1]", "negative index \\[-1\\]"),
    ],
)
def test_parse_key_path_refuses_malformed_keys(key, match):
    with pytest.raises(ConfigError, match=match) as info:
        mut.parse_key_path(key, "w")
    assert str(info.value).startswith(f"w: malformed key '{key}'")


def test_overrides_set_one_list_item_and_keep_the_rest():
    dut = mut.apply_overrides(
        Schema,
        Schema(),
        [
            "position[0]=0.55",
            "position[2]=-1",
            "grid[1][0]=9",
            "pushes[1].force[2]=5",
            "pushes[0].time=1.5",
            "inner.names=[x, y]",
            "inner.names[1]='z: w'",
            "table={a: [1, 2]}",
            "table.a[1]=7",
        ],
    )
    assert dut.position == [0.55, 2.0, -1.0]
    assert dut.grid == [[1.0, 2.0], [9.0, 4.0]]
    assert dut.pushes == [Push(time=1.5), Push(time=2.0, force=[0.0, 0.0, 5.0])]
    assert dut.inner.names == ["x", "z: w"]
    assert dut.table == {"a": [1.0, 7.0]}
    assert dut.rate == Schema().rate and dut.count == Schema().count
    # An item that is a section takes a mapping, merged like any section.
    assert mut.apply_overrides(Schema, dut, ["pushes[1]={time: 3}"]).pushes[1] == Push(
        time=3.0, force=[0.0, 0.0, 5.0]
    )


@pytest.mark.parametrize(
    "bad, match",
    [
        ("position[3]=1", "'position' has no item \\[3\\] \\(it has 3 items\\)"),
        ("grid[0][2]=1", "'grid\\[0\\]' has no item \\[2\\] \\(it has 2 items\\)"),
        ("inner.names[0]=x", "'inner.names' has no item \\[0\\] \\(it has 0 items\\)"),
        ("position[-1]=1", "negative index \\[-1\\]"),
        ("rate[0]=1", "'rate' is float 0.5, not a list"),
        ("inner[0]=1", "'inner' is a mapping, not a list"),
        ("position[0].x=1", "'position\\[0\\]' is float 1.0, not a mapping"),
        ("bogus[0]=1", "unknown key 'bogus' \\(known here: count,"),
        ("inner.bogus[0]=1", "unknown key 'inner.bogus'"),
        ("pushes[0].bogus=1", "unknown key 'pushes\\[0\\].bogus'"),
        ("pushes[0].bogus.x=1", "unknown key 'pushes\\[0\\].bogus'"),
        ("position[0]=x", "'position\\[0\\]' must be a number"),
        ("position[0]=.nan", "'position\\[0\\]' must be finite"),
        ("position[0]=1, 2", "'position\\[0\\]' must be a number"),
        ("position[0]=[1", "malformed YAML"),
        ("position[=1", "malformed key 'position\\['"),
        ("position]=1", "malformed key 'position\\]'"),
        ("position[a]=1", "malformed key 'position\\[a\\]'"),
    ],
)
def test_indexed_overrides_refuse_bad_keys_naming_them(bad, match):
    before = Schema()
    with pytest.raises(ConfigError, match=match) as info:
        mut.apply_overrides(Schema, before, [bad])
    assert str(info.value).startswith(f"--set {bad!r}: ")
    assert before == Schema()  # the value overridden is never changed in place


def test_set_with_an_index_on_the_command_line():
    """Every app's ``--set`` goes through ``apply_overrides``: pick-and-place's, for one."""
    command = [sys.executable, "-m", "drake_sim.pickplace", "--print-scenario"]
    ok = subprocess.run(
        [*command, "--set", "scene.object.position[0]=0.55"], capture_output=True, text=True
    )
    assert ok.returncode == 0, ok.stderr
    default = yaml.safe_load(subprocess.run(command, capture_output=True, text=True).stdout)
    position = yaml.safe_load(ok.stdout)["scene"]["object"]["position"]
    assert position == [0.55, *default["scene"]["object"]["position"][1:]]
    assert default["scene"]["object"]["position"][0] != 0.55
    bad = subprocess.run(
        [*command, "--set", "scene.object.position[3]=0.55"], capture_output=True, text=True
    )
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines() == [
        "error: --set 'scene.object.position[3]=0.55': 'scene.object.position' has no item [3] "
        "(it has 3 items)"
    ]


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
