import pytest

from oceanloc.config.survey import PlannerSettings
from oceanloc.errors import ConfigError, DataError
from oceanloc.field.survey.settings import JournalSettings
from oceanloc.geo.enu import EnuOrigin


def test_settings_round_trip_through_meta():
    s = JournalSettings(
        planner=PlannerSettings(kind="lookahead", horizon=3, max_distance_m=7.5),
        speed_mps=1.5,
        origin=EnuOrigin(lat_deg=32.705, lon_deg=-117.236, h_m=-1.478),
        beacons=(1, 2),
        prior_sigma_enu_m=(50.0, 60.0, 5.0),
        heading_deg=123.4,
    )
    meta = s.to_meta()
    assert meta["planner"] == '"lookahead"' and meta["beacons"] == "[1, 2]"
    assert JournalSettings.from_meta(meta) == s
    assert JournalSettings.from_meta(JournalSettings().to_meta()) == JournalSettings()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"speed_mps": -1.0}, "speed_mps must be a positive number, got -1.0"),
        ({"sigma_range_m": float("nan")}, "sigma_range_m must be a positive number, got nan"),
        ({"prior_sigma_enu_m": (1.0, 0.0, 1.0)}, "prior_sigma_enu_m needs 3 positive values"),
        ({"sound_speed_mps": 340.0}, "sound_speed_mps 340.0 is outside"),
        ({"beacons": (1, 1)}, "beacons must be distinct"),
        ({"heading_deg": 1000.0}, "heading_deg must be in"),
    ],
)
def test_impossible_settings_name_the_field(kwargs, message):
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(")", r"\)")):
        JournalSettings(**kwargs)


def test_malformed_meta_names_the_journal_and_key():
    meta = JournalSettings().to_meta()
    with pytest.raises(DataError, match=r"s\.db: survey setting 'speed_mps' missing"):
        JournalSettings.from_meta({k: v for k, v in meta.items() if k != "speed_mps"}, "s.db")
    with pytest.raises(DataError, match="'period_s' is not valid JSON"):
        JournalSettings.from_meta(meta | {"period_s": "fast"}, "s.db")
    with pytest.raises(DataError, match=r"malformed survey settings .*speed_mps must be a positive"):
        JournalSettings.from_meta(meta | {"speed_mps": "-2"}, "s.db")
