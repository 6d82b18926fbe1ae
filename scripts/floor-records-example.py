#!/usr/bin/env python3
"""Writes docs/data/floor-records-example.json: synchronous floor force records in windmeta's format
for the ten-storey building of docs/data/tower10-3d.json (30 m by 20 m, 4 m storeys), as a 1:200
pressure model in a 10 m/s flow would give them, made of sines so that every value is known in
closed form:

  force along the wind  F = q b h (1.3 + 0.26 sin(2 pi 1.1 t) + 0.13 sin(2 pi 3.7 t + 1)) (z/H)^0.3
  across-wind force     L = q b h 0.25 sin(2 pi f_s t) (z/H)^0.3,  f_s = 0.1 U / b (Strouhal 0.1)
  torque                T = q b^2 h 0.05 sin(2 pi f_s t + 0.5) (z/H)^0.3

with q = rho U^2 / 2 (rho = 1.2 kg/m3), b the model's face across the wind, h its storey height,
z/H the floor's height over the roof's, for wind towards 0 deg (along x, facing the 20 m depth) and
towards 90 deg (along y, facing the 30 m breadth). Standard library only:
    python3 scripts/floor-records-example.py
"""
import json
import math
import pathlib

SCALE = 200.0
SPEED = 10.0
DENSITY = 1.2
RATE = 200.0
SAMPLES = 480
FLOORS = 10
STOREY = 4.0 / SCALE
PLAN = (30.0 / SCALE, 20.0 / SCALE)


def value(x):
    return float(f"{x:.4g}")


def direction(degrees, facing):
    q = 0.5 * DENSITY * SPEED**2
    shedding = 0.1 * SPEED / facing
    floors = []
    for j in range(1, FLOORS + 1):
        profile = (j / FLOORS) ** 0.3
        drag, lift, torque = [], [], []
        for k in range(SAMPLES):
            t = k / RATE
            drag.append(value(q * facing * STOREY * profile * (1.3 + 0.26 * math.sin(2 * math.pi * 1.1 * t) + 0.13 * math.sin(2 * math.pi * 3.7 * t + 1))))
            lift.append(value(q * facing * STOREY * profile * 0.25 * math.sin(2 * math.pi * shedding * t)))
            torque.append(value(q * facing**2 * STOREY * profile * 0.05 * math.sin(2 * math.pi * shedding * t + 0.5)))
        # The drag acts along the wind, the across-wind force along (-sin, cos) of it.
        if degrees == 0:
            floors.append({"force_x_n": drag, "force_y_n": lift, "torque_n_m": torque})
        else:
            floors.append({"force_x_n": [-v for v in lift], "force_y_n": drag, "torque_n_m": torque})
    return {"wind_direction_deg": degrees, "floors": floors}


data = {
    "format": "floor_force_records",
    "length_scale": SCALE,
    "model_roof_speed_m_s": SPEED,
    "model_air_density_kg_m3": DENSITY,
    "sampling_rate_hz": RATE,
    "directions": [direction(0, PLAN[1]), direction(90, PLAN[0])],
}
path = pathlib.Path(__file__).resolve().parent.parent / "docs" / "data" / "floor-records-example.json"
path.write_text(json.dumps(data, separators=(",", ":")) + "\n")
print(f"wrote {path}")
