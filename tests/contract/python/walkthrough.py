"""The README's walkthrough through a Python client generated from openapi/openapi.yaml.

    python walkthrough.py BASE_URL API_KEY

Run by tests/contract/run.sh with the generated package `windmeta_client` on PYTHONPATH, against a
real server. Each answer is checked as a design office's script would rely on it, with closed forms
where there are some; the last line printed is the calibrated metamodel's id. docs/clients.md shows
the same calls.
"""

import math
import sys
import time

from windmeta_client import AuthenticatedClient
from windmeta_client.api.analyses import fragility, hazard
from windmeta_client.api.calibrations import start_calibration
from windmeta_client.api.metamodels import exceedance_curve, get_study
from windmeta_client.api.operations import get_operation
from windmeta_client.api.presets import list_presets
from windmeta_client.models import (
    CalibrationRequest,
    ExceedanceAnswer,
    ExceedanceRequest,
    ExceedanceRequestFixed,
    FragilityAnswer,
    FragilityRequest,
    HazardAnswer,
    HazardRequest,
    Operation,
    OperationState,
    PresetList,
    ProblemDetails,
    ReturnPeriodSpeeds,
    ReturnPeriodSpeedsReturnPeriodSpeeds,
)


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def is_curve(answer, samples):
    """An exceedance curve: probabilities in [0, 1], non-increasing, inside their band."""
    p = answer.probabilities
    check(answer.samples == samples, f"{answer.samples} samples, asked {samples}")
    check(len(p) == len(answer.thresholds) == len(answer.lower) == len(answer.upper), "ragged curve")
    check(all(0.0 <= x <= 1.0 for x in p), f"probabilities outside [0, 1]: {p}")
    check(all(a >= b for a, b in zip(p, p[1:])), f"an exceedance curve cannot rise: {p}")
    check(all(lo <= x <= hi for lo, x, hi in zip(answer.lower, p, answer.upper)), "a probability outside its band")


def follow(client, operation, limit_s=300):
    """Polls an operation until it is done, as the Location header of a 202 invites."""
    started = time.monotonic()
    while not operation.done:
        check(time.monotonic() - started < limit_s, f"operation {operation.id} stuck: {operation.state}")
        time.sleep(0.2)
        operation = get_operation.sync(operation.id, client=client)
        check(isinstance(operation, Operation), f"reading the operation: {operation}")
    return operation


def main(base_url, api_key):
    client = AuthenticatedClient(base_url=base_url, token=api_key, raise_on_unexpected_status=True)

    presets = list_presets.sync(client=client)
    check(isinstance(presets, PresetList), f"presets: {presets}")
    names = [preset.name for preset in presets.presets]
    check("frame40-kn" in names, f"presets: {names}")

    # A small calibration (the paper's is CalibrationRequest(preset="frame40-kn"): 200 storms of 900 s).
    request = CalibrationRequest(preset="frame40-kn", experiments=32, duration_s=120.0, seed=1)
    started = start_calibration.sync_detailed(client=client, body=request)
    check(started.status_code == 202, f"calibration: {started.status_code} {started.content!r}")
    check(started.headers["location"] == f"/v1/operations/{started.parsed.id}", "Location names the operation")
    done = follow(client, started.parsed)
    check(done.state == OperationState.SUCCEEDED, f"calibration ended {done.state}: {done.error}")
    metamodel = done.metamodel_id
    study = get_study.sync(metamodel, client=client)
    check(study.floors == 40, f"a 40-storey study: {study.floors}")

    # The exceedance curve of the peak roof displacement at a 35 m/s wind, as JSON.
    fixed = ExceedanceRequestFixed.from_dict({"wind_speed": 35.0})
    curve = exceedance_curve.sync(metamodel, client=client, body=ExceedanceRequest(samples=200, fixed=fixed, seed=1))
    check(isinstance(curve, ExceedanceAnswer), f"exceedance: {curve}")
    is_curve(curve, 200)
    check(curve.confidence == 0.95, f"confidence {curve.confidence}")

    # Annual answers under a climate given by two return-period speeds: the Gumbel law drawn
    # through them gives each speed its return period back, P(annual max > v_T) = 1 − exp(−1/T).
    speeds = {"50": 31.0, "700": 33.0}
    climate = ReturnPeriodSpeeds(return_period_speeds=ReturnPeriodSpeedsReturnPeriodSpeeds.from_dict(speeds))
    annual = hazard.sync(
        metamodel, client=client, body=HazardRequest(climate=climate, samples=120, seed=4, return_periods=[10.0, 100.0])
    )
    check(isinstance(annual, HazardAnswer), f"hazard: {annual}")
    law = annual.climate.to_dict()
    check(law["distribution"] == "gumbel", f"climate: {law}")
    for years, speed in speeds.items():
        survival = -math.expm1(-math.exp(-(speed - law["location"]) / law["scale"]))
        exact = -math.expm1(-1.0 / float(years))
        check(abs(survival / exact - 1.0) < 1e-9, f"the {years}-year speed is exceeded with {survival}, not {exact}")
    p = annual.annual_probability
    check(all(a >= b for a, b in zip(p, p[1:])), f"an annual exceedance curve cannot rise: {p}")
    check(len(annual.return_levels) == 2, f"return levels: {annual.return_levels}")

    # Fragility: P(peak > x | v) over wind speeds, with the band of each probability.
    wind_speeds = [24.0, 30.0, 36.0]
    fragile = fragility.sync(
        metamodel, client=client, body=FragilityRequest(wind_speeds=wind_speeds, thresholds=[0.05], samples=40)
    )
    check(isinstance(fragile, FragilityAnswer), f"fragility: {fragile}")
    check(fragile.wind_speeds == wind_speeds and fragile.samples_per_speed == 40, "fragility grid")
    for curve in fragile.curves:
        check(len(curve.probability) == len(wind_speeds), "one probability per speed")
        check(all(lo <= x <= hi for lo, x, hi in zip(curve.lower, curve.probability, curve.upper)), "band")

    # A request the server refuses: problem+json, read as the client's ProblemDetails, naming the field.
    refused = exceedance_curve.sync_detailed(metamodel, client=client, body=ExceedanceRequest(samples=0))
    check(refused.status_code == 422, f"samples 0: {refused.status_code}")
    problem = refused.parsed
    check(isinstance(problem, ProblemDetails), f"samples 0: {problem}")
    check([error.field for error in problem.errors] == ["samples"], f"the field at fault: {problem.to_dict()}")

    print("the walkthrough passed through the generated Python client", file=sys.stderr)
    print(metamodel)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
