"""T-year levels of reference peaks sampled on a site's climate, with distribution-free bands.

Reads the JSON of `windmeta sample-peaks --spec SPEC --json` (storms whose wind speed is drawn from
the climate's law of the annual maximum) and prints, for each return period T, the peaks' quantile
at p = exp(-1/T) (the order statistic of rank ceil(n p)) and the 95 % interval of the order
statistics that covers that quantile whatever the law (ranks from the binomial(n, p) distribution).
Standard library only.

    python3 tests/reference/return_levels.py peaks.json 1 10
"""

import json
import math
import sys


def binomial_cdf(k, n, p):
    """P(B <= k) for B ~ binomial(n, p), summed in logs."""
    if k < 0:
        return 0.0
    terms = [
        math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1) + i * math.log(p) + (n - i) * math.log1p(-p)
        for i in range(0, min(k, n) + 1)
    ]
    top = max(terms)
    return min(1.0, math.exp(top) * sum(math.exp(t - top) for t in terms))


def level(peaks, period, confidence=0.95):
    """The T-year level and its distribution-free band (None where the sample is too small)."""
    n = len(peaks)
    p = math.exp(-1.0 / period)
    tail = (1.0 - confidence) / 2.0
    rank = max(1, math.ceil(n * p))
    # x_(l) <= quantile with probability P(B >= l) = 1 - F(l - 1); the largest such l with F(l-1) <= tail.
    lower = max((r for r in range(1, n + 1) if binomial_cdf(r - 1, n, p) <= tail), default=None)
    upper = min((r for r in range(1, n + 1) if binomial_cdf(r - 1, n, p) >= 1.0 - tail), default=None)
    at = lambda r: None if r is None else peaks[r - 1]
    return at(rank), at(lower), at(upper)


def main():
    document = json.load(open(sys.argv[1]))
    peaks = sorted(document["peaks"] if isinstance(document, dict) else document)
    for period in map(float, sys.argv[2:]):
        value, lower, upper = level(peaks, period)
        print(f"{period:g} years: {value:.4f} [{lower:.4f}, {upper:.4f}] from {len(peaks)} storms")


if __name__ == "__main__":
    main()
