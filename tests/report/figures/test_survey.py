def test_round_magnification_is_one_two_or_five_times_a_power_of_ten():
    from oceanloc.report.figures.survey import _round_magnification

    assert [_round_magnification(f) for f in (0.5, 1.0, 3.7, 19.9, 20.0, 480.0)] == [1, 1, 2, 10, 20, 200]
