"""The README's "Your own data" section says what data/units.py enforces (issue 45: a newcomer's
first file was refused for a negative force_n, and nothing in the README said why)."""
import re
from pathlib import Path

from data.units import UNITS, physical_range

README = Path(__file__).resolve().parents[2] / "README.md"


def own_data_section() -> str:
    text = README.read_text()
    return text.split("## Your own data", 1)[1].split("\n## ", 1)[0]


def test_every_unit_word_is_listed_in_the_readme():
    listed = set(re.findall(r"`_(\w+)`", own_data_section()))
    assert set(UNITS) - {"ohms"} <= listed, sorted(set(UNITS) - listed)   # ohms: a spelling of ohm


def test_the_readmes_examples_follow_the_rules():
    section = own_data_section()
    assert "`force_n` ≥ 0" in section and physical_range("force_n").low == 0
    assert "`delta_force_n` may be negative" in section and physical_range("delta_force_n") is None
    assert "positions (`x_mm`)" in section and physical_range("x_mm") is None
    assert "force components (`shear_x_n`)" in section and physical_range("shear_x_n") is None
    assert "temperature `_degc` ≥ −273.15" in section and physical_range("t_degc").low == -273.15


def test_the_readme_example_names_the_settings_a_table_run_needs():
    section = own_data_section()
    for setting in ("data=table", "data.path=", "data.target_columns=", "data.group_columns=", "predict.py"):
        assert setting in section, setting
