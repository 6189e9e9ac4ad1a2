from rich.console import Console

from oceanloc.config.catalog import builtin_scenarios, load_scenario
from oceanloc.report.tables.scenarios import format_value, scenario_list_table, scenario_show_table


def _render(renderable) -> str:
    console = Console(record=True, width=100)
    console.print(renderable)
    return console.export_text()


def test_list_covers_every_kind_and_fits_100_columns():
    text = _render(scenario_list_table(builtin_scenarios()))
    assert all(len(line) <= 100 for line in text.splitlines())
    for name in ("garcia2019-m4", "garcia2018-greedy-m1", "dillard-filters", "dillard-drift-swap"):
        assert name in text
    assert {"survey", "flock", "drift"} <= set(text.split())


def test_show_prints_transponder_and_start_rows():
    # numpy 2 scalars used to reach rich as markup and print blank rows
    text = _render(scenario_show_table(load_scenario("garcia2019-m4")))
    assert "[17, 15, -6]" in text and "[-9, 13, -8]" in text
    assert "start (E, N, U) m" in text and "[-3, 9, 0]" in text
    assert "k = 2" in text


def test_show_flock_and_drift_scenarios():
    flock = _render(scenario_show_table(load_scenario("dillard-filters")))
    assert "nodes.radius_m" in flock and "200" in flock
    drift = _render(scenario_show_table(load_scenario("dillard-drift-swap")))
    assert "start_m" in drift and "[-3500, 3500]" in drift


def test_toml_values_are_escaped(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(
        '[scenario]\nname = "x[/x]"\ndescription = "[sensor] table [/b]"\nepochs = 3\n'
        "[vehicle]\nstart_enu_m = [0.0, 0.0, 0.0]\n[sensor]\nsigma_range_m = 0.1\n"
        "[prior]\nsigma_enu_m = [1.0, 1.0, 1.0]\n[[transponders]]\nenu_m = [1.0, 2.0, -3.0]\n"
    )
    text = _render(scenario_show_table(load_scenario(path)))
    assert "[sensor] table [/b]" in text and "x[/x]" in text


def test_format_value_handles_numpy_scalars():
    import numpy as np

    assert format_value(np.float64(0.12)) == "0.12" and format_value(np.int64(3)) == "3"
    assert format_value(np.array([1.5, -2.0])) == "[1.5, -2]"
