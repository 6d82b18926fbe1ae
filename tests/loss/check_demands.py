"""A demand sample of `windmeta demands`, read by pelicun and read as plain CSV: pelicun must find
every column (peak floor accelerations of floors 0..n in g, peak drift ratios of storeys 1..n in
rad) and every storm, with the file's values; the ground's acceleration is 0.

    python check_demands.py demands.csv FLOORS
"""

import csv
import math
import sys

from pelicun.assessment import Assessment


def main(path: str, floors: int) -> None:
    with open(path, newline="") as file:
        rows = list(csv.reader(file))
    header, units, storms = rows[0], rows[1], rows[2:]
    assert header[0] == "" and units[0] == "Units", (header[:2], units[:2])
    expected = [f"1-PFA-{j}-1" for j in range(floors + 1)] + [f"1-PID-{j}-1" for j in range(1, floors + 1)]
    assert header[1:] == expected, header[:5]
    assert units[1:] == ["g"] * (floors + 1) + ["rad"] * floors, units[:5]
    assessment = Assessment({"PrintLog": False, "Verbose": False})
    assessment.demand.load_sample(path)
    sample = assessment.demand.save_sample()
    assert sample.shape == (len(storms), 2 * floors + 1), sample.shape
    for name, column in zip(header[1:], zip(*(row[1:] for row in storms))):
        _, kind, location, direction = name.split("-")
        read = sample[(kind, location, direction)].to_numpy()
        for storm, (mine, theirs) in enumerate(zip(column, read)):
            assert math.isclose(float(mine), theirs, rel_tol=1e-12, abs_tol=1e-300), (name, storm, mine, theirs)
    assert all(float(row[1]) == 0.0 for row in storms), "the ground does not move"
    assert all(float(v) > 0.0 for row in storms for v in row[2:]), "every floor and storey moves"
    print(f"pelicun read {len(storms)} storms of {2 * floors + 1} demands, as written")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))
