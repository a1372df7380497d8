"""The largest parametric work drydem accepts, each limit defined once here (a light module: the
command line reads them for its options and help without loading numpy), and why.

Both limits are far beyond what a study needs and well within what the results can hold; a
larger count is much more likely a slip (a range written with too fine a step, a digit too
many) than an intent, and it would otherwise start a run of months, or hang while it is laid out.
"""

from __future__ import annotations

from drydem.model.parameters import Range

#: the most runs a study (``drydem sweep``) makes, all its grids together. Each run is a record
#: file in one folder (RESULTS/runs/ID.json) that a sweep looks at before it starts and the
#: report reads whole; the study is checked run by run before its first run (about 5 s per 10^5
#: runs); and 10^5 tilting analyses of even the smallest wall are a day of one core. A larger
#: study is split into several study files, which may share one --out
MAX_RUNS = 10**5
#: the most samples of a Monte Carlo run (``drydem montecarlo --samples``). The sampling error of
#: the statistics falls as 1 / sqrt(n): at 10^5 samples that of the mean is 0.3 % of the standard
#: deviation and that of the 5th percentile under 1 % of it (normal scatter), finer than any tilt
#: step; and OUT/summary.json lists every sample (about 22 MB at 10^5), which the report and a
#: resumed run read whole
MAX_SAMPLES = 10**5
#: the rule of a Monte Carlo run's number of samples
SAMPLES = Range(1, MAX_SAMPLES, integer=True)
#: MAX_SAMPLES's reason in a few words, for messages and --help
SAMPLES_REASON = ("the statistics' sampling error is then under 1 % of the standard deviation, and summary.json lists every "
                  "sample")
