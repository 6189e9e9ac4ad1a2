"""A small Monte Carlo of closed-loop transponder surveys: planned (k = 2) against the random baseline.

The scenario is written as TOML (the format of ``oceanloc scenarios show garcia2019-m1``: one transponder,
journal Table II), once with the look-ahead planner and once with random yaw rates (the journal's k = 0),
and each is run 16 times over 20 epochs in this process with ``survey_monte_carlo``. Prints the RMSEE
(eq. 45) and mean ``log det Y_n`` at the last epoch, and the NEES check against chi-square(3).
"""

import tempfile
from pathlib import Path

from oceanloc.config.survey import load_survey_scenario
from oceanloc.evaluation.survey import survey_monte_carlo

SCENARIO = """
[scenario]
name = "one-transponder-{kind}"
epochs = 20

[vehicle]
start_enu_m = [-3.0, 9.0, 0.0]
start_yaw_deg = -30.0             # counter-clockwise from east
speed_mps = 3.0
period_s = 1.0
max_yaw_rate_deg_s = 30.0

[sensor]
sigma_range_m = 0.12

[prior]
sigma_enu_m = [100.0, 100.0, 2.0]

[[transponders]]
enu_m = [17.0, 15.0, -6.0]

[planner]
kind = "{kind}"
horizon = 2
"""

with tempfile.TemporaryDirectory() as tmp:
    for kind in ("lookahead", "random-yaw"):
        path = Path(tmp, f"{kind}.toml")
        path.write_text(SCENARIO.format(kind=kind))
        scenario = load_survey_scenario(path)
        mc = survey_monte_carlo(scenario, runs=16, seed=2019)
        n = scenario.epochs
        low, high = mc.nees_final.mean_band
        print(
            f"{kind:>10}: RMSEE at n={n} {mc.rmsee_m[-1, 0]:.3f} m, "
            f"mean log det Y_n {mc.log_det.mean[-1]:.2f}, "
            f"mean NEES {mc.nees_final.mean:.2f} (chi-square 3 band {low:.2f}-{high:.2f}), "
            f"{100 * mc.converged_fraction:.1f} % of MAP solves converged"
        )
