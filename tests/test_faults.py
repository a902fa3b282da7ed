"""Cable faults of the control API (omsd/faults.py): validation and seeded damage."""

from __future__ import annotations

import pytest

from omsd.faults import Faults


def test_no_faults_pass_bytes_untouched() -> None:
    assert Faults().damage(b"AX MR100 GO") == b"AX MR100 GO"


def test_drop_everything_and_nothing() -> None:
    assert Faults(drop=1.0).damage(b"x" * 100) == b""
    assert Faults(drop=0.0, garble=0.0).damage(b"abc") == b"abc"


def test_garble_flips_one_bit_per_damaged_byte_and_is_repeatable() -> None:
    data = bytes(range(256)) * 4
    a = Faults(garble=0.5, seed=7).damage(data)
    b = Faults(garble=0.5, seed=7).damage(data)
    assert a == b and len(a) == len(data)
    flipped = [x ^ y for x, y in zip(a, data, strict=True) if x != y]
    assert 300 < len(flipped) < 724
    assert all(bin(f).count("1") == 1 for f in flipped)
    assert Faults(garble=0.5, seed=8).damage(data) != a


def test_baud_gives_characters_per_second() -> None:
    assert Faults(baud=9600).chars_per_second == 960.0
    assert Faults().chars_per_second is None


@pytest.mark.parametrize(
    "kwargs",
    [{"latency": -1.0}, {"latency": 61.0}, {"baud": 10}, {"drop": 1.5}, {"garble": -0.1}],
)
def test_bad_settings_are_refused_in_one_line(kwargs: dict[str, float]) -> None:
    with pytest.raises(ValueError) as info:
        Faults(**kwargs)  # type: ignore[arg-type]
    assert "\n" not in str(info.value)
