"""The crack table a fracture user reads: units, one row per tip and ring named by its
radii, J and G, the reference and the difference from it, the law and loads, the signs."""

import math

import pytest

from xfem_contact.io.crack_report import Reference, crack_table, k_unit


def ring(r_inf, r_sup, K_I, K_II, J, G):
    return {"r_inf": r_inf, "r_sup": r_sup, "K_I": K_I, "K_II": K_II, "J": J, "G": G}


TIPS = [
    {
        "position": [0.2285, 0.1332],
        "direction": [0.866, 0.5],
        "rings": [ring(0.1, 0.3, 7.2e5, 4.0e5, 2.9, 2.95), ring(0.2, 0.5, 7.1e5, 4.0e5, 2.8, 2.9)],
    },
    {
        "position": [-0.2045, -0.1168],
        "direction": [-0.866, -0.5],
        "rings": [ring(0.1, 0.3, -2.0e4, 4.1e5, 0.8, 0.75)],
    },
]


def test_rows_name_tip_and_ring_with_units_and_reference():
    reference = Reference(8.0e5, 4.0e5, "Griffith, infinite plate")
    lines = crack_table(
        "crack", TIPS, {"law": "free"}, "traction on 'top' (0, 1e+06) Pa", reference, 2.3e11
    )
    assert lines[0] == "crack 'crack': law of the lips free"
    assert lines[1] == "  loads: traction on 'top' (0, 1e+06) Pa"
    assert "K in MPa m^1/2, J and G in J/m^2" in lines[2]
    assert lines[3].split() == ["tip", "ring", "K_I", "K_II", "J", "G", "K_I", "vs", "ref"] + [
        "K_II",
        "vs",
        "ref",
    ]
    rows = [line.split() for line in lines[4:9]]
    # tip, ring r_inf..r_sup, K_I, K_II (MPa m^1/2), J, G, K / K_ref - 1 per mode
    assert rows[0] == ["0", "0.1..0.3", "0.7200", "0.4000", "2.9", "2.95", "-10.00%", "+0.00%"]
    assert rows[1] == ["0", "0.2..0.5", "0.7100", "0.4000", "2.8", "2.9", "-11.25%", "+0.00%"]
    G_ref = (8.0e5**2 + 4.0e5**2) / 2.3e11
    assert rows[2] == ["0", "reference", "0.8000", "0.4000", f"{G_ref:.4g}"]
    assert rows[3][:4] == ["1", "0.1..0.3", "-0.0200", "0.4100"]
    assert rows[4][:2] == ["1", "reference"]
    notes = " ".join(lines[9:])
    assert "tip 0 at (0.2285, 0.1332) m, tip 1 at (-0.2045, -0.1168) m" in notes
    assert "the rings agree to 1.4 % of max |K| per tip" in notes  # (7.2 - 7.1) / 7.2
    assert "reference: Griffith, infinite plate" in notes
    assert "K_I > 0 opens the lips" in notes
    # free lips with K_I < 0 interpenetrate: the table says so
    assert f"K_I < 0 with free lips (down to {-100 * 2e4 / math.hypot(2e4, 4.1e5):.2g} %" in notes
    assert all(len(line) <= 104 for line in lines[9:])


def test_contact_law_explains_negative_K_I_and_prints_the_law():
    law = {"law": "coulomb", "augmentation": 1.0, "friction": 0.3}
    lines = crack_table("crack", TIPS, law)
    assert lines[0] == "crack 'crack': law of the lips coulomb (augmentation 1, friction 0.3)"
    assert not any("loads:" in line or "vs ref" in line for line in lines)
    notes = " ".join(" ".join(lines).split())
    assert "closed lips carry K_I = 0 in the exact solution" in notes
    assert (
        "a small negative K_I of closed lips is the discretisation's (here down to -4.9 %" in notes
    )
    assert "free lips" not in notes


def test_zero_reference_mode_is_compared_with_the_magnitude():
    reference = Reference(0.0, -2.0e6)
    assert reference.difference("K_II", -2.2e6) == pytest.approx(0.1)  # K / K_ref - 1
    assert reference.difference("K_I", -5.0e4) == pytest.approx(-0.025)  # of |K_ref|
    assert math.isnan(Reference(0.0, 0.0).difference("K_I", 1.0))
    with pytest.raises(ValueError, match="reference K_I must be a number"):
        Reference("1e6", 0.0)
    with pytest.raises(ValueError, match="reference K_II must be finite"):
        Reference(1e6, math.nan)


@pytest.mark.parametrize(
    "values, unit", [([2.9e6, -1e3], "MPa m^1/2"), ([450.0], "kPa m^1/2"), ([0.8, 0.2], "Pa m^1/2")]
)
def test_unit_follows_the_largest_K(values, unit):
    assert k_unit(values)[1] == unit
