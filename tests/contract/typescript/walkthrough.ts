// The README's walkthrough through a TypeScript client generated from openapi/openapi.yaml:
// openapi-typescript writes the contract's types (generated/windmeta.d.ts), openapi-fetch calls the
// routes with them. tests/contract/run.sh type-checks it with `tsc` and runs it against a real server:
//   node build/walkthrough.js BASE_URL API_KEY
import createClient from "openapi-fetch";
import type { components, paths } from "./generated/windmeta.js";

type Operation = components["schemas"]["Operation"];

function check(condition: boolean, message: string): asserts condition {
  if (!condition) throw new Error(message);
}

const [baseUrl, apiKey] = process.argv.slice(2);
check(baseUrl !== undefined && apiKey !== undefined, "usage: node build/walkthrough.js BASE_URL API_KEY");
// JSON answers only (the routes also answer CSV and SVG by `Accept`): data and errors are typed as JSON.
const client = createClient<paths, `application/${string}json`>({
  baseUrl,
  headers: { Authorization: `Bearer ${apiKey}` },
});

/** Polls an operation until it is done, as the Location header of a 202 invites. */
async function follow(operation: Operation): Promise<Operation> {
  const started = Date.now();
  while (!operation.done) {
    check(Date.now() - started < 300_000, `operation ${operation.id} stuck: ${operation.state}`);
    await new Promise((resolve) => setTimeout(resolve, 200));
    const { data, error } = await client.GET("/v1/operations/{id}", { params: { path: { id: operation.id } } });
    check(data !== undefined, `reading the operation: ${JSON.stringify(error)}`);
    operation = data;
  }
  return operation;
}

const presets = await client.GET("/v1/presets");
check(presets.data?.presets.some((preset) => preset.name === "frame40-kn") === true, "the presets name frame40-kn");

// A small calibration (the paper's is { preset: "frame40-kn" }: 200 storms of 900 s).
const started = await client.POST("/v1/calibrations", {
  body: { preset: "frame40-kn", experiments: 32, duration_s: 120, seed: 1 },
});
check(started.response.status === 202 && started.data !== undefined, `calibration: ${JSON.stringify(started.error)}`);
check(started.response.headers.get("location") === `/v1/operations/${started.data.id}`, "Location names the operation");
const calibrated = await follow(started.data);
check(calibrated.state === "succeeded" && typeof calibrated.metamodel_id === "string", `calibration: ${calibrated.error}`);
const id = calibrated.metamodel_id;

// The exceedance curve of the peak roof displacement at a 35 m/s wind, as JSON.
const curve = await client.POST("/v1/metamodels/{id}/exceedance", {
  params: { path: { id } },
  body: { samples: 200, fixed: { wind_speed: 35 }, seed: 1 },
});
const answer = curve.data;
check(answer !== undefined && "probabilities" in answer, `exceedance: ${JSON.stringify(curve.error)}`);
check(answer.samples === 200, `${answer.samples} samples`);
check(answer.probabilities.every((p, i) => p >= 0 && p <= 1 && p >= (answer.probabilities[i + 1] ?? 0)), "a curve");

// Annual answers under a climate given by two return-period speeds: the Gumbel law drawn through
// them gives each speed its return period back, P(annual max > v_T) = 1 − exp(−1/T).
const speeds: Record<string, number> = { "50": 31, "700": 33 };
const annual = await client.POST("/v1/metamodels/{id}/hazard", {
  params: { path: { id } },
  body: { climate: { return_period_speeds: speeds }, samples: 120, seed: 4, return_periods: [10, 100] },
});
// 200 is the answer, 202 an operation (a request above the server's synchronous limit): `in` tells.
check(annual.data !== undefined && "climate" in annual.data, `hazard: ${JSON.stringify(annual.error)}`);
const law = annual.data.climate;
check(law.distribution === "gumbel", `a Gumbel law: ${JSON.stringify(law)}`);
for (const [years, speed] of Object.entries(speeds)) {
  const survival = -Math.expm1(-Math.exp(-(speed - law.location) / law.scale));
  const exact = -Math.expm1(-1 / Number(years));
  check(Math.abs(survival / exact - 1) < 1e-9, `the ${years}-year speed is exceeded with ${survival}, not ${exact}`);
}

// Fragility: P(peak > x | v) over wind speeds.
const fragility = await client.POST("/v1/metamodels/{id}/fragility", {
  params: { path: { id } },
  body: { wind_speeds: [24, 30, 36], thresholds: [0.05], samples: 40 },
});
check(fragility.data !== undefined && "curves" in fragility.data, `fragility: ${JSON.stringify(fragility.error)}`);
for (const curve of fragility.data.curves) {
  check(curve.probability.length === 3, "one probability per speed");
  check(curve.probability.every((p, i) => (curve.lower[i] ?? 1) <= p && p <= (curve.upper[i] ?? 0)), "a band");
}

// A request the server refuses: problem+json, typed as the contract's ProblemDetails.
const refused = await client.POST("/v1/metamodels/{id}/exceedance", { params: { path: { id } }, body: { samples: 0 } });
const problem: components["schemas"]["ProblemDetails"] | undefined = refused.error;
check(refused.response.status === 422 && problem?.errors?.[0]?.field === "samples", `samples 0: ${JSON.stringify(problem)}`);

console.error("the walkthrough passed through the generated TypeScript client");
