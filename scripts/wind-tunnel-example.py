#!/usr/bin/env python3
"""Writes docs/data/wind-tunnel-example.json: force-balance data in windmeta's format whose spectra
are known in closed form, so that tests can check what windmeta reads and simulates from it.

Every spectrum is one peak of the form the published across-wind model uses,
F(n) = 4(1 + 0.6 b) b / pi * x^2 / ((1 - x^2)^2 + 4 b^2 x^2), x = n / n_s,
whose area over ln n is (1 + 0.6 b)(pi/2 + asin(1 - 2 b^2)) / (pi sqrt(1 - b^2)).
The tests hold the same peaks (n_s, b) as constants. Standard library only:
    python3 scripts/wind-tunnel-example.py
"""
import json
import math
import pathlib


def peak(n, shedding, beta):
    x2 = (n / shedding) ** 2
    return 4 * (1 + 0.6 * beta) * beta / math.pi * x2 / ((1 - x2) ** 2 + 4 * beta**2 * x2)


# 30 points a decade from 1e-3 to 10.
FREQUENCIES = [10 ** (-3 + k / 30) for k in range(121)]


def component(rms, shedding, beta):
    return {
        "rms_coefficient": rms,
        "reduced_frequencies": [float(f"{n:.6g}") for n in FREQUENCIES],
        "spectrum": [float(f"{peak(float(f'{n:.6g}'), shedding, beta):.6g}") for n in FREQUENCIES],
    }


data = {
    "reference_breadth_m": 24.4,
    "vertical_coherence_decay": 0.5,
    "directions": [
        {
            "wind_direction_deg": 0,
            "across_wind": component(0.15, 0.10, 0.25),
            "torsion": component(0.05, 0.15, 0.40),
            "coherence": 0.3,
        },
        {
            "wind_direction_deg": 90,
            "across_wind": component(0.20, 0.09, 0.30),
            "torsion": component(0.06, 0.15, 0.40),
            "coherence": {"reduced_frequencies": [0.01, 1.0], "values": [0.1, 0.4]},
        },
    ],
}
path = pathlib.Path(__file__).resolve().parent.parent / "docs" / "data" / "wind-tunnel-example.json"
path.write_text(json.dumps(data, indent=1) + "\n")
print(f"wrote {path}")
