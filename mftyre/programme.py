"""Recognise the test programme in measured data before anything is fitted to it.

:func:`recognise` answers what a tyre-test engineer reads off a measurement first: which load, pressure, camber
(and speed) levels were tested, which channel each test sweeps and in which direction, which rows are steady
and which are transitions between conditions, and so which effects the data can determine.

Levels (:func:`cluster_levels`) are the modes of the distribution of a condition channel: a histogram of
bin width set by the channel's own short-term scatter (samples against the median of their four neighbours,
over the samples that scatter at all: exact plateaus, ramps and staircases say nothing about it; for point
data that step every row between settings, the scatter within the groups the sorted values form, separated by
empty room), smoothed, whose
peaks are merged only when the valley between them is shallow (above half the lower peak). A level is
therefore separated from its neighbour by the empty room between them, however close they are relative to
the largest value (1650 / 2200 / 2750 N with a few percent scatter are three levels), and a slow ramp between
levels is no level. Samples far from every level (more than 4 robust standard deviations of their nearest
level, and more than the bin width; when an exact plateau sits beside visits that scatter, those visits'
spread) are off-level (label -1): ramps, load sweeps, transients. With a handful
of points (< 50) distinct values whose separations are far below the others (a jump of 8x in the sorted
separations) are merged: repeated settings that scatter; so are levels of a sampled run at a jump of 4x (runs
pooled, each setting its nominal pressure or load a few percent off: 0.69 / 0.71 / 0.93 / 0.96 bar are two
pressures), the grouping relative to the programme's own steps, no fixed tolerance. Values in no order (50 or more) that form no groups and
lie flat over their range (a table of random points) hold no level: :attr:`Programme.spread` gives their range,
which determines load, pressure or camber terms as levels do.

In a time series (:func:`recognise`; TIME at 20 Hz or more) the levels are found from the held samples only
(the local range over +-w samples, w = 0.25 s, within 5 short-term standard deviations and 2 % of the range),
so that ramps and load sweeps make no level of their own; every sample then gets the level of its stay: the
sequence of levels (or off-level) with the least misfit plus a penalty per change (Viterbi), so that a wander of
the load scatter towards the next level does not end a stay and a ramp that passes a level quickly does not make
one. A run at a level that is mostly not held and crosses half its range from its first fifth to its last is a
ramp; an off-level excursion between two stays at one level whose samples all lie nearest to it belongs to
the stay. Only levels at which a test ran (a sweep or steady point) are levels of the programme: a warm-up or
parking load is none.

Segments and sweeps (:func:`recognise`): a new segment starts where the level of load, pressure or camber
changes (an off-level run is a segment of its own; runs shorter than 2 s between two stays at the same levels
are excursions of the scatter and belong to them). Within a segment, each row is given the channel among SA, SL,
VX that moves most relative to its sweep threshold (1 deg, 0.02, 3 m/s) over +-w rows; runs of that label are
the candidate sweeps. A short run (a reversal, a blip) between two runs of the same channel, and a run where
nothing moves that is shorter than both (a dwell at the end of a sweep), joins them. A slip-ratio run is split
by the levels of the slip angle held (combined slip at several angles), a slip-angle run by those of the slip
ratio. A run is a sweep when its range (isolated spikes removed) exceeds the channel's threshold and spans at
least half the widest range of that channel in any run (a shorter move, such as steering to the slip angle of
a combined-slip test, is a transition). Slip and speed sweeps run at held conditions; a load sweep is an
off-level run that goes up and down, each way over 3/4 of its range, and covers at least the span of the load
levels (unloading to change the pressure is no load sweep). The direction (BRANCH +1 up / -1 down) is the sign
of the change over a window of 5 % of the sweep's length. Segments where nothing moves beyond the thresholds,
held for 2 s or more (for point data: the short run below), are steady points; others are transitions. The
short run is 0.2 % of the data (at least 50 samples in a time series, 2 rows otherwise).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .data import TyreData
from .lazy import LazyModule

pd = LazyModule("pandas")  # imported when first used: the command line starts without it

__all__ = ["cluster_levels", "recognise", "Programme", "SWEEP_THRESHOLD"]

#: range above which a channel counts as swept within a segment (SI units)
SWEEP_THRESHOLD = {"SA": math.radians(1.0), "SL": 0.02, "VX": 3.0}
#: the kind of test by swept channel
_KIND = {"SA": "slip_angle", "SL": "slip_ratio", "VX": "speed", "FZ": "load"}


# ------------------------------------------------------------------------------------------------- levels
def _short_term_scatter(x: np.ndarray, *, every_row: bool = True) -> float:
    """Short-term standard deviation of a channel in its order (0 when < 20 values): the robust spread of each
    sample about the median of its four neighbours, over the samples that scatter at all. The sample itself is
    left out of that median (a median that includes it returns it wherever the samples run monotonically, so
    that noisy data show ~40 % exact zeros); samples on an exact plateau (a generated warm-up) or in a monotone
    run of five (a ramp, a staircase of settings) tell nothing about the scatter and are left out too. Noise
    leaves 98 % of the samples (of white noise) in no monotone run, exact settings only the few at their
    reversals and resets: when fewer than a quarter remain, the scatter is 0 (exact settings). ``every_row``: when the spread exceeds 5 % of the
    range, neighbouring rows may be settings repeated in no order (the channel steps every row between them): the
    scatter within the groups they form (:func:`_settings_scatter`), if they form any; values that form none (one
    noisy level in no order, a table of random points) keep the spread about their neighbours. A time series has
    no such channel (``every_row=False``): a single noisy level (a speed held at 16.7 +- 0.02 m/s) is noise."""
    scatter = _neighbour_scatter(x)
    if not every_row or scatter <= 0.05 * float(np.ptp(x)):
        return scatter
    settings = _settings_scatter(x)
    return scatter if settings is None else settings


def _neighbour_scatter(x: np.ndarray) -> float:
    """The robust spread of each sample about the median of its four neighbours (see :func:`_short_term_scatter`),
    0 when fewer than 20 values or exact settings."""
    if x.size < 20:
        return 0.0
    padded = np.pad(x, 2, mode="reflect")
    window = np.stack([padded[:-4], padded[1:-3], padded[2:-2], padded[3:-1], padded[4:]])
    dev = np.abs(x - np.median(window[[0, 1, 3, 4]], axis=0))
    steps = np.diff(window, axis=0)
    monotone = np.all(steps >= 0, axis=0) | np.all(steps <= 0, axis=0)
    scatters = (dev > 1e-9 * max(float(np.max(np.abs(x))), 1e-300)) & ~monotone
    if scatters.sum() < max(10, 0.25 * x.size):
        return 0.0
    return _MAD_TO_SD / _NEIGHBOUR_MEDIAN_GAIN * float(np.median(dev[scatters]))


def _settings_scatter(x: np.ndarray) -> float | None:
    """The scatter of settings repeated in no order (point data stepping every row between them): the median robust
    standard deviation of the groups of three or more values, when the sorted values fall into two or more such groups
    separated by empty room (a gap more than :data:`_SETTINGS_ROOM` times the median of the 40 gaps around it and
    of all gaps: the few values at either end of a range leave no window of their own);
    None when they do not: one noisy level (a speed held at 16.7 +- 0.02 m/s, shuffled) or values spread over a
    range (a table of random points), whose gaps grow smoothly (into the tails of a normal scatter too). (The
    distance to the third-nearest value, used before, is the spacing of the values, not the scatter of a setting:
    with 200 values per setting it is ~25 times smaller, and one noisy setting split into several.)"""
    v = np.sort(x)
    gaps = np.diff(v)
    from scipy.ndimage import median_filter

    around = np.maximum(median_filter(gaps, size=41, mode="nearest"), np.median(gaps))
    cut = np.flatnonzero(gaps > _SETTINGS_ROOM * around)
    groups = [g for g in np.split(v, cut + 1) if g.size >= 3]
    if len(groups) < 2:
        return None
    return float(np.median([_MAD_TO_SD * np.median(np.abs(g - np.median(g))) for g in groups]))


#: Empty room between repeated settings, in local gaps (a gap of independent values exceeds 20 times the median
#: of its neighbours with probability ~e^-14)
_SETTINGS_ROOM = 20.0


_MAD_TO_SD = 1.4826  # standard deviation / median absolute deviation of a normal distribution
#: |x - median of its 4 neighbours| of white noise (monotone runs of five left out) has 1.166 times the median
#: absolute deviation of x itself
_NEIGHBOUR_MEDIAN_GAIN = 1.166


def _spread(values: np.ndarray, centre: float) -> float:
    """Robust standard deviation of a level's values (in their order) about its centre, 0 when none. When a
    fifth or more of them (and at least 20) scatter while the others sit on values held exactly over
    consecutive samples (an exact plateau such as a generated warm-up, beside visits to the level that
    scatter), the spread of those that scatter, if larger: the plateau would otherwise collapse it to 0."""
    if values.size == 0:
        return 0.0
    spread = _MAD_TO_SD * float(np.median(np.abs(values - centre)))
    same = values[1:] == values[:-1]
    free = ~(np.concatenate([[False], same]) | np.concatenate([same, [False]]))
    if free.sum() >= max(20, 0.2 * values.size):
        spread = max(spread, _MAD_TO_SD * float(np.median(np.abs(values[free] - centre))))
    return spread


def _spread_over_a_range(x: np.ndarray) -> bool:
    """Unordered values (neighbours as different as any two: the spread about the neighbours' median above 5 %
    of the range) that form no groups of repeated settings (:func:`_settings_scatter`) and lie flat over their
    range rather than peaked about one value as the noise of a held level does: the 2.5-97.5 % range over the
    interquartile range below :data:`_FLAT_TAILS` (a normal scatter 2.9, uniform values 1.9). A table of random
    points: no level at all."""
    if _neighbour_scatter(x) <= 0.05 * float(np.ptp(x)) or _settings_scatter(x) is not None:
        return False
    q = np.percentile(x, [2.5, 25.0, 75.0, 97.5])
    return bool(q[3] - q[0] < _FLAT_TAILS * (q[2] - q[1]))


_FLAT_TAILS = 2.4


def cluster_levels(values, *, scatter: float | None = None):
    """Cluster the values of a condition channel into levels: (labels, centres).

    ``labels``: level index per value (sorted by centre), -1 for off-level values (ramps, sweeps, transients)
    and for NaN; ``centres``: the mean of each level's values. ``scatter``: the short-term scatter of the
    channel (default: estimated from the values in their order; give it for unordered values). See the module
    text for the rule; no tolerance relative to the largest value is involved.
    """
    x = np.asarray(values, dtype=float)
    labels = np.full(x.size, -1, int)
    ok = np.isfinite(x)
    xs = x[ok]
    if xs.size == 0:
        return labels, np.zeros(0)
    span = float(np.ptp(xs))
    scale = max(float(np.max(np.abs(xs))), 1e-300)
    if span <= 1e-9 * scale:
        labels[ok] = 0
        return labels, np.array([float(np.mean(xs))])
    s = _short_term_scatter(xs) if scatter is None else float(scatter)
    if scatter is None and xs.size >= 50 and _spread_over_a_range(xs):
        return labels, np.zeros(0)
    h = max(s, 1e-3 * span, 1e-12 * scale)
    nbins = int(min(max(span / (h / 2.0), 8), 20000))
    edges = np.linspace(xs.min(), xs.max(), nbins + 1)
    counts, _ = np.histogram(xs, edges)
    from scipy.ndimage import gaussian_filter1d

    width_bins = h / (edges[1] - edges[0])
    dens = gaussian_filter1d(counts.astype(float), max(width_bins, 0.5), mode="constant") if xs.size >= 50 \
        else counts.astype(float)
    peaks = _peaks(dens)
    peaks = _merge_shallow(dens, peaks)
    # basins: each bin belongs to the peak whose valley bounds enclose it
    bounds = [0] + [int(np.argmin(dens[a:b + 1]) + a) for a, b in zip(peaks[:-1], peaks[1:])] + [nbins]
    mass = np.array([counts[lo:hi].sum() for lo, hi in zip(bounds[:-1], bounds[1:])], float)
    keep = mass >= (1.0 if xs.size < 50 else max(3.0, 0.05 * mass.max()))
    centres_guess = 0.5 * (edges[np.array(peaks)] + edges[np.array(peaks) + 1])[keep]
    # centre and spread of each level from the values nearest to it
    idx = _nearest(xs, centres_guess)
    centres = np.array([np.median(xs[idx == k]) for k in range(centres_guess.size)])
    if centres.size > 2:  # few points: repeated settings that scatter; a sampled run: one setting made twice
        centres = _merge_scatter(xs, centres, 8.0 if xs.size < 50 else 4.0)
    idx = _nearest(xs, centres)
    lab = np.full(xs.size, -1, int)
    out_centres = []
    for k in range(centres.size):
        sel = idx == k
        sd = _spread(xs[sel], centres[k])
        near = sel & (np.abs(xs - centres[k]) <= max(4.0 * sd, h, 1e-9 * scale))
        if near.any():
            lab[near] = len(out_centres)
            out_centres.append(float(np.mean(xs[near])))
    labels[ok] = lab
    return labels, np.array(out_centres)


def _assign(x, lab, centres):
    """Labels of all values: those of the held values, and for the others the nearest level when within the
    spread (4 robust standard deviations, at least the level's own range) of its held values."""
    out = lab.copy()
    free = (lab < 0) & np.isfinite(x)
    if centres.size == 0 or not free.any():
        return out
    near = _nearest(x[free], centres)
    reach = np.array([max(4.0 * _spread(x[lab == k], centres[k]),
                          float(np.ptp(x[lab == k]))) if np.any(lab == k) else 0.0 for k in range(centres.size)])
    ok = np.abs(x[free] - centres[near]) <= reach[near]
    out[np.flatnonzero(free)[ok]] = near[ok]
    return out


def _stays(x, lab, centres, *, penalty, block):
    """Labels of a time series of a condition channel by its stays at the levels: the sequence of states
    (a level or off-level, -1) that minimises the misfit, ((x - centre) / spread)^2 / 2 at a level (at most
    12.5, 5 spreads) and 4.5 off-level (3 spreads), plus ``penalty`` per change of state (Viterbi, on medians of
    ``block`` samples). A wander of the load scatter towards the next level does not end a stay; a ramp that
    passes a level quickly does not make one. ``lab``: labels of the held samples (their spread per level)."""
    n = x.size
    spread = np.array([_spread(x[lab == k], c) for k, c in enumerate(centres)])
    gaps = np.diff(np.sort(centres))
    spread = np.maximum(spread, 1e-9 * max(float(np.max(np.abs(centres))), 1e-300))
    if gaps.size:
        spread = np.maximum(spread, 1e-3 * float(gaps.min()))
    m = -(-n // block)
    pad = np.concatenate([x, np.full(m * block - n, np.nan)]).reshape(m, block)
    with np.errstate(all="ignore"):
        xm = np.nanmedian(pad, axis=1)
    cost = np.minimum(0.5 * ((xm[:, None] - centres[None, :]) / spread[None, :]) ** 2, 12.5)
    cost = np.concatenate([cost, np.full((m, 1), 4.5)], axis=1)
    cost[~np.isfinite(xm)] = 0.0
    cost[~np.isfinite(xm), -1] = -1.0  # NaN: off-level
    cost *= block
    k = cost.shape[1]
    back = np.zeros((m, k), np.int32)
    total = cost[0].copy()
    for t in range(1, m):
        best = int(np.argmin(total))
        switch = total[best] + penalty
        stay = total <= switch
        back[t] = np.where(stay, np.arange(k), best)
        total = np.where(stay, total, switch) + cost[t]
    state = np.empty(m, np.int32)
    state[-1] = int(np.argmin(total))
    for t in range(m - 1, 0, -1):
        state[t - 1] = back[t, state[t]]
    out = np.where(state == k - 1, -1, state)
    return np.repeat(out, block)[:n]


def _nearest(x, centres):
    if centres.size == 0:
        return np.full(x.size, -1, int)
    return np.argmin(np.abs(x[:, None] - centres[None, :]), axis=1)


def _peaks(dens):
    """Indices of the local maxima of ``dens`` (a plateau counts once, at its middle)."""
    d = np.diff(np.concatenate([[-1.0], dens, [-1.0]]))
    up = np.flatnonzero(d[:-1] > 0)
    peaks = []
    for i in up:
        j = i
        while j + 1 < dens.size and dens[j + 1] == dens[i]:
            j += 1
        if j + 1 >= dens.size or dens[j + 1] < dens[i]:
            peaks.append((i + j) // 2)
    return sorted(set(p for p in peaks if dens[p] > 0))


def _merge_shallow(dens, peaks):
    """Merge neighbouring peaks whose valley stays above half the lower peak."""
    peaks = list(peaks)
    changed = True
    while changed and len(peaks) > 1:
        changed = False
        for i in range(len(peaks) - 1):
            a, b = peaks[i], peaks[i + 1]
            valley = float(np.min(dens[a:b + 1]))
            if valley > 0.5 * min(dens[a], dens[b]):
                peaks[i:i + 2] = [a if dens[a] >= dens[b] else b]
                changed = True
                break
    return peaks


def _merge_scatter(x, centres, factor: float = 8.0):
    """Merge neighbouring levels whose separation is far (``factor``) below the next larger separation: the
    sorted separations break into the steps of the programme and the scatter of its settings (few points that
    scatter, 8x; in sampled runs, e.g. two runs pooled, each setting a nominal level again a few percent off, 4x:
    0.69 / 0.71 / 0.93 / 0.96 bar are two pressures)."""
    centres = np.sort(centres)
    sep = np.diff(centres)
    order = np.sort(sep)
    ratio = order[1:] / np.maximum(order[:-1], 1e-300)
    k = int(np.argmax(ratio))
    if ratio[k] < factor:
        return centres
    limit = order[k]
    group = np.concatenate([[0], np.cumsum(sep > limit)])  # group of each centre
    member = group[_nearest(x, centres)]
    return np.array([float(np.mean(x[member == g])) for g in range(group[-1] + 1)])


# -------------------------------------------------------------------------------------------- programme
@dataclass
class Programme:
    """The recognised test programme of a data set (see :func:`recognise`).

    ``levels``: channel -> level centres (FZ, P, IA; VX of the slip tests); ``sweeps``: one row per segment
    (start, stop row, kind, swept channel, n rows, direction changes, the level centres held, branch counts);
    ``rows``: per-row DataFrame with SEGMENT, SWEEP (segment number of swept segments, -1 otherwise), KIND,
    BRANCH (+1 up, -1 down, 0 held), STEADY (bool), FZ_LEVEL, P_LEVEL, IA_LEVEL (index into ``levels``, -1
    off-level); ``sample_rate`` [Hz] when a TIME channel is present;
    ``fittable``: stage group -> bool; ``notes``: what cannot be determined and why; ``spread``: condition channel
    -> (least, greatest) value where the values lie spread over a range with no level (a table of random points).
    """

    levels: dict
    sweeps: pd.DataFrame
    rows: pd.DataFrame
    n_rows: int
    sample_rate: float | None = None
    has: dict = field(default_factory=dict)
    fittable: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    sl_max: float = 0.0  # largest |SL| in the data: "no longitudinal slip" is said only when it is noise
    spread: dict = field(default_factory=dict)  # FZ, P, IA spread over a range by random points: (lo, hi), no level

    def count(self, kind: str) -> int:
        """Number of sweeps of a kind (slip_angle, slip_ratio, speed, load, steady)."""
        return int((self.sweeps["kind"] == kind).sum()) if len(self.sweeps) else 0

    def annotate(self, data: TyreData) -> TyreData:
        """``data`` with the per-row columns of ``rows`` added (replacing any of the same name)."""
        frame = data.frame.copy()
        for c in self.rows.columns:
            frame[c] = self.rows[c].to_numpy()
        return data.with_frame(frame, "test programme recognised: " + self.summary(short=True))

    def summary(self, short: bool = False) -> str:
        """One paragraph: '5 loads 450-2750 N, 3 pressures 0.83-0.97 bar, ...; fittable: ...'."""
        parts = []
        for ch, name, fac, unit, digits in (("FZ", "load", 1.0, "N", 0), ("P", "pressure", 1e-5, "bar", 2),
                                            ("IA", "camber", 180 / math.pi, "deg", 1), ("VX", "speed", 1.0, "m/s", 1)):
            c = np.round(self.levels.get(ch, np.zeros(0)) * fac, digits) + 0.0  # + 0.0: no "-0.0"
            if c.size == 0 and ch in self.spread:
                lo, hi = (round(v * fac, digits) + 0.0 for v in self.spread[ch])
                parts.append(f"{name}s spread over {lo:.{digits}f} to {hi:.{digits}f} {unit} (no level)")
            elif c.size == 0:
                parts.append(f"no {name} level")
            elif c.size == 1:
                parts.append(f"1 {name} {c[0]:.{digits}f} {unit}")
            else:
                parts.append(f"{c.size} {name}s {c.min():.{digits}f} to {c.max():.{digits}f} {unit}")
        for kind, what in (("slip_angle", "slip-angle sweeps"), ("slip_ratio", "slip-ratio sweeps"),
                           ("speed", "speed sweeps"), ("load", "vertical load sweeps")):
            k = self.count(kind)
            parts.append(f"{k} {what}" if k else f"no {what}")
        steady = self.count("steady")
        if steady:
            parts.append(f"{steady} steady segments")
        if self.sl_max <= SWEEP_THRESHOLD["SL"]:
            parts.append("no longitudinal slip")  # SL zero throughout but for measurement noise
        elif not self.has.get("longitudinal_slip"):
            parts.append(f"longitudinal slip in isolated samples only (|SL| up to {self.sl_max:.3g})")
        text = ", ".join(parts)
        if self.sample_rate:
            text += f"; sampled at {self.sample_rate:.0f} Hz"
        if short:
            return text
        yes = [k for k, v in self.fittable.items() if v]
        no = [k for k, v in self.fittable.items() if not v]
        text += f"; fittable: {', '.join(yes) or 'nothing'}"
        if no:
            text += f"; not fittable: {', '.join(no)}"
        return text

    def __str__(self):
        return self.summary()


def _runs(key: np.ndarray):
    """(start, stop) of the runs of equal rows of a 2-D integer key."""
    if len(key) == 0:
        return []
    change = np.any(key[1:] != key[:-1], axis=1)
    starts = np.concatenate([[0], np.flatnonzero(change) + 1])
    stops = np.concatenate([starts[1:], [len(key)]])
    return list(zip(starts.tolist(), stops.tolist()))


def _direction(x: np.ndarray) -> np.ndarray:
    """+1 up, -1 down, 0 held per sample: the sign of the change of x over a centred window of 5 % of the run,
    0 where the change is within the dead band (5 short-term standard deviations, at least 2 % of the range)."""
    n = x.size
    w = max(1, int(round(0.025 * n)))
    padded = np.concatenate([np.full(w, x[0]), x, np.full(w, x[-1])])
    change = padded[2 * w:] - padded[:-2 * w]
    band = max(5.0 * _short_term_scatter(x), 0.02 * float(np.ptp(x)))
    return np.where(np.abs(change) > band, np.sign(change), 0).astype(int)


def _in_steps(x: np.ndarray) -> bool:
    """Whether ``x`` moves in steps: three rows or more up and down, the median change from row to row within a
    quarter of its range and none beyond half of it (random values jump by a third of theirs, some across it)."""
    d = _direction(x)
    step = np.abs(np.diff(x))
    return int(np.sum(d > 0)) >= 3 and int(np.sum(d < 0)) >= 3 \
        and float(np.median(step)) <= 0.25 * float(np.ptp(x)) and float(np.max(step)) <= 0.5 * float(np.ptp(x))


def _reversals(d: np.ndarray) -> int:
    moving = d[d != 0]
    return int(np.sum(moving[1:] != moving[:-1])) if moving.size > 1 else 0


def _local_range(x: np.ndarray, w: int) -> np.ndarray:
    """Range of ``x`` (median-filtered over w + 1 samples against noise) in the centred window of +-w samples."""
    from scipy.ndimage import maximum_filter1d, median_filter, minimum_filter1d

    if w > 1:
        x = median_filter(x, size=w + 1, mode="nearest")
    size = 2 * w + 1
    return maximum_filter1d(x, size, mode="nearest") - minimum_filter1d(x, size, mode="nearest")


def _held(x: np.ndarray, w: int, every_row: bool = True) -> np.ndarray:
    """Samples at which ``x`` is held (its local range within 5 short-term standard deviations and 2 % of its
    range), all samples when fewer than 50 or when under 20 % would be held (point data stepping every row).
    ``every_row``: see :func:`_short_term_scatter`."""
    ok = np.isfinite(x)
    if x.size < 50 or not ok.all() or np.ptp(x) == 0:
        return ok
    held = _local_range(x, w) <= max(5.0 * _short_term_scatter(x, every_row=every_row), 0.02 * float(np.ptp(x)))
    return held if held.mean() >= 0.2 else ok


def _moving_channel(channels: dict, w: int) -> np.ndarray:
    """Per row: index (1-based, in the order of ``channels``) of the slip or speed channel changing most
    relative to its sweep threshold over +-w rows (at least a tenth of the threshold), 0 where none moves."""
    score = np.stack([_local_range(x, w) / SWEEP_THRESHOLD[ch] for ch, x in channels.items()], axis=1)
    best = np.argmax(score, axis=1)
    return np.where(score[np.arange(len(best)), best] > 0.1, best + 1, 0)


def _merge_gaps(label: np.ndarray, short: int) -> np.ndarray:
    """Runs of ``label`` between two runs of the same label are absorbed by them when shorter than ``short``
    (a reversal, a blip of noise) or, when nothing moves in them, shorter than both neighbours (a dwell at the
    end of a sweep)."""
    label = label.copy()
    changed = True
    while changed:
        changed = False
        runs = _runs(label[:, None])
        for i in range(1, len(runs) - 1):
            (a0, a1), (b0, b1), (c0, c1) = runs[i - 1], runs[i], runs[i + 1]
            if label[a0] != label[c0] or label[a0] == 0:
                continue
            m = b1 - b0
            if m < short or (label[b0] == 0 and m <= min(a1 - a0, c1 - c0)):
                label[b0:b1] = label[a0]
                changed = True
                break
    return label


def _span(x: np.ndarray) -> float:
    """Range of ``x`` without isolated spikes (after a running median of 5, of 3 under 20 samples)."""
    from scipy.ndimage import median_filter

    return float(np.ptp(median_filter(x, size=5 if x.size >= 20 else 3, mode="mirror"))) if x.size > 1 else 0.0


def _up_and_down(x: np.ndarray) -> bool:
    """Whether ``x`` goes up and down (or down and up), each way over at least 3/4 of its range (unloading
    to change the pressure and loading to the next condition is no load sweep)."""
    half = 0.75 * float(np.ptp(x))
    i, j = int(np.argmax(x)), int(np.argmin(x))
    return any(np.ptp(x[:k + 1]) >= half and np.ptp(x[k:]) >= half for k in (i, j))


def recognise(data: TyreData) -> Programme:
    """Recognise the test programme of ``data`` (rows in measurement order): levels, segments, sweeps with
    their direction, steady and transient rows, and what is fittable. See the module text for the rules."""
    n = len(data)
    cond_ch = ("FZ", "P", "IA")
    sample_rate = None
    if "TIME" in data.frame.columns:
        t = pd.to_numeric(data.frame["TIME"], errors="coerce").to_numpy(float)
        dt = np.diff(t)
        dt = dt[np.isfinite(dt) & (dt > 0)]
        if dt.size:
            sample_rate = 1.0 / float(np.median(dt))
    time_series = sample_rate is not None and sample_rate >= 20
    short_run = max(50, int(0.002 * n)) if time_series else max(2, int(0.002 * n))
    steady_run = 4 * short_run if time_series else short_run  # 2 s at 100 Hz
    w = max(1, short_run // 2)  # half-window of the local change (0.25 s at 100 Hz)
    labels, levels, spread = {}, {}, {}
    for ch in cond_ch:
        x = data.array(ch)
        held = _held(x, w, every_row=not time_series)
        ok = held & np.isfinite(x)
        scatter = _short_term_scatter(x[ok], every_row=False) if time_series else None
        lab, centres = cluster_levels(np.where(ok, x, np.nan), scatter=scatter)  # levels from the held samples
        if scatter is None and not centres.size and np.count_nonzero(ok) >= 50 and _spread_over_a_range(x[ok]):
            spread[ch] = (float(np.min(x[ok])), float(np.max(x[ok])))
        if time_series and centres.size:
            lab = _stays(x, lab, centres, penalty=4.0 * short_run, block=max(1, short_run // 5))
        else:
            lab = _assign(x, lab, centres)
        # a run at a level that is a ramp passing through it: mostly not held, and from its first fifth to its
        # last it crosses half its range
        for a, b in _runs(lab[:, None]):
            fifth = max(1, (b - a) // 5)
            if lab[a] >= 0 and held[a:b].mean() < 0.5 and abs(np.median(x[b - fifth:b]) - np.median(
                    x[a:a + fifth])) >= 0.5 * np.ptp(x[a:b]):
                lab[a:b] = -1
        # an excursion of the scatter beyond a level's spread that stays nearest to it belongs to the stay
        runs = _runs(lab[:, None])
        for (a0, _), (a, b), (c, _) in zip(runs[:-2], runs[1:-1], runs[2:]):
            if lab[a] < 0 and lab[a0] == lab[c] >= 0 and np.all(_nearest(x[a:b], centres) == lab[a0]):
                lab[a:b] = lab[a0]
        labels[ch], levels[ch] = lab, centres
    key = np.stack([labels[ch] for ch in cond_ch], axis=1) if n else np.zeros((0, 3), int)
    runs = _runs(key)
    long_runs = [i for i, (a, b) in enumerate(runs) if b - a >= steady_run]
    for i, j in zip(long_runs[:-1], long_runs[1:]):
        before, after = key[runs[i][0]], key[runs[j][0]]
        if j > i + 1 and np.array_equal(before, after) and np.all(before >= 0):
            key[runs[i][1]:runs[j][0]] = before  # brief excursions off a level (scatter) do not end the stay
    for i, (start, stop) in enumerate(runs):
        if 0 < i < len(runs) - 1 and stop - start < short_run and key[start, 0] >= 0 \
                and key[runs[i - 1][0], 0] < 0 and key[runs[i + 1][0], 0] < 0:
            key[start:stop, 0] = -1  # a ramp passing through a level is no stay at that level
    seg_id = np.full(n, -1, int)
    sweep_id = np.full(n, -1, int)
    kind = np.full(n, "transition", object)
    branch = np.zeros(n, int)
    rows = []
    sa, sl, vx, fz = (data.array(c) for c in ("SA", "SL", "VX", "FZ"))
    n_sweeps = 0
    pieces = []
    for start, stop in _runs(key):
        # within a stay at one condition: runs of the channel that moves (slip angle, slip ratio or speed),
        # each split further by the levels of the slip channel held (slip-ratio sweeps at several slip angles)
        sub = slice(start, stop)
        moving = _merge_gaps(_moving_channel({"SA": sa[sub], "SL": sl[sub], "VX": vx[sub]}, w), short_run)
        for a, b in _runs(moving[:, None]):
            held_ch = {1: sl, 2: sa}.get(int(moving[a]))
            if held_ch is None or b - a < 4:
                pieces.append((start + a, start + b))
                continue
            hx = held_ch[start + a:start + b]
            thr = SWEEP_THRESHOLD["SL" if held_ch is sl else "SA"]
            lab = cluster_levels(hx)[0] if np.ptp(hx) > thr else np.zeros(b - a, int)
            lab = _merge_gaps(lab + 1, short_run)  # 0: off-level
            for c, d in _runs(lab[:, None]):
                pieces.append((start + a + c, start + a + d))
    widest = {ch: max([_span(x[a:b]) for a, b in pieces] + [0.0]) for ch, x in (("SA", sa), ("SL", sl), ("VX", vx))}
    widest["FZ"] = max([_span(fz[a:b]) for a, b in pieces if np.any(key[a] < 0)] + [0.0])
    for seg, (start, stop) in enumerate(pieces):
        sub = slice(start, stop)
        m = stop - start
        seg_id[sub] = seg
        off_level = bool(np.any(key[start] < 0))
        ranges = {ch: _span(x[sub]) for ch, x in (("SA", sa), ("SL", sl), ("VX", vx), ("FZ", fz))}
        thresholds = dict(SWEEP_THRESHOLD, FZ=abs(float(np.mean(fz[sub]))) / 3.0 + 1e-9)
        # a sweep spans at least half the widest range of its channel; a shorter move (e.g. steering to the
        # slip angle of a combined-slip test) is a transition
        score = {ch: ranges[ch] / thresholds[ch] for ch in ranges if ranges[ch] > thresholds[ch]
                 and ranges[ch] >= 0.5 * widest[ch]}
        # slip and speed sweeps run at held conditions; a load sweep goes up and down off the load levels over
        # at least their span (a one-way load change is the ramp between two conditions, unloading to change
        # the pressure a dip), in steps (the loads of a table of random points jump up and down every row)
        score = {ch: v for ch, v in score.items() if (ch == "FZ") == off_level}
        if "FZ" in score and not (_up_and_down(fz[sub]) and _in_steps(fz[sub])
                                  and ranges["FZ"] >= (np.ptp(levels["FZ"]) if levels["FZ"].size else 0.0)):
            score.pop("FZ")
        swept = max(score, key=score.get) if score else None
        moving = any(ranges[ch] > SWEEP_THRESHOLD[ch] for ch in ("SA", "SL", "VX"))
        if swept is None and (off_level or moving):
            k = "transition"  # off-level, or a slip or speed changing without being a sweep
        elif swept is None:
            k = "steady" if m >= steady_run else "transition"  # too brief to be a measured steady point
        else:
            k = _KIND[swept]
        kind[sub] = k
        d = np.zeros(m, int)
        if swept is not None and k != "transition":
            d = _direction((sa, sl, vx, fz)[("SA", "SL", "VX", "FZ").index(swept)][sub])
            branch[sub] = d
            sweep_id[sub] = n_sweeps
            n_sweeps += 1
        rows.append(dict(segment=seg, start=start, stop=stop, n=m, kind=k, swept=swept,
                         reversals=_reversals(d),
                         up=int(np.sum(d > 0)), down=int(np.sum(d < 0)),
                         FZ=float(np.mean(fz[sub])), P=float(np.mean(data.array("P")[sub])),
                         IA=float(np.mean(data.array("IA")[sub])), SA=float(np.median(sa[sub])),
                         SL=float(np.median(sl[sub])), VX=float(np.median(vx[sub]))))
    sweeps = pd.DataFrame(rows)
    steady = np.isin(kind, ("steady", "slip_angle", "slip_ratio", "speed", "load"))
    # the levels of the programme are those at which a test ran (a warm-up or parking load is none)
    tested = steady & np.all(key >= 0, axis=1)
    for i, ch in enumerate(cond_ch):
        used = np.unique(key[tested, i])
        if levels[ch].size and used.size:
            remap = np.full(levels[ch].size, -1, int)
            remap[used] = np.arange(used.size)
            key[:, i] = np.where(key[:, i] >= 0, remap[np.maximum(key[:, i], 0)], -1)
            levels[ch] = levels[ch][used]
    per_row = pd.DataFrame({"SEGMENT": seg_id, "SWEEP": sweep_id, "KIND": kind, "BRANCH": branch, "STEADY": steady,
                            **{f"{ch}_LEVEL": key[:, i] for i, ch in enumerate(cond_ch)}})
    slip_tests = np.isin(kind, ("slip_angle", "slip_ratio", "steady"))
    vx_tests = vx[slip_tests & np.isfinite(vx)]
    levels["VX"] = cluster_levels(vx_tests, scatter=_short_term_scatter(vx_tests, every_row=False) if time_series
                                  else None)[1] if vx_tests.size else np.zeros(0)
    def beyond(x, threshold):  # slip applied on purpose: more than a few noise spikes beyond the threshold
        return bool(np.sum(np.abs(x) > threshold) >= max(10, 0.005 * n))

    has = dict(
        lateral_slip=beyond(sa, SWEEP_THRESHOLD["SA"]),
        longitudinal_slip=beyond(sl, SWEEP_THRESHOLD["SL"]),
        camber=bool(np.any(np.abs(np.r_[levels["IA"], spread.get("IA", ())]) > math.radians(0.25))),
        speed_sweep=bool(np.any(kind == "speed")),
        loaded_radius=data.has("RL"), effective_radius=data.has("RE"),
        fx=data.has("FX"), fy=data.has("FY"), mz=data.has("MZ"), mx=data.has("MX"), my=data.has("MY"))
    prog = Programme(levels=levels, sweeps=sweeps, rows=per_row, n_rows=n, sample_rate=sample_rate, has=has,
                     sl_max=float(np.nanmax(np.abs(sl))) if n else 0.0, spread=spread)
    prog.fittable, prog.notes = _fittable(prog)
    return prog


def _fittable(prog: Programme):
    h, lv = prog.has, prog.levels
    n_loads = lv["FZ"].size
    out, notes = {}, []

    def rule(name, ok, why):
        out[name] = bool(ok)
        if not ok:
            notes.append(f"{name}: {why}")

    rule("pure Fx", h["longitudinal_slip"] and h["fx"], "no longitudinal slip" if not h["longitudinal_slip"]
         else "no FX channel")
    rule("pure Fy", h["lateral_slip"] and h["fy"], "no slip angle" if not h["lateral_slip"] else "no FY channel")
    rule("Mz", h["lateral_slip"] and h["mz"], "no slip angle" if not h["lateral_slip"] else "no MZ channel")
    combined = bool(len(prog.sweeps)) and bool(((prog.sweeps["kind"] == "slip_ratio")
                                                & (prog.sweeps["SA"].abs() > SWEEP_THRESHOLD["SA"])).any())
    rule("combined slip", combined, "no slip-ratio sweep at a non-zero slip angle")
    rule("load terms", n_loads >= 2 or "FZ" in prog.spread, f"{n_loads} load level(s)")
    rule("pressure terms", lv["P"].size >= 2 or "P" in prog.spread, f"{lv['P'].size} pressure level(s)")
    rule("camber terms", h["camber"], "no camber level other than zero")
    rule("Mx", h["mx"], "no MX channel")
    rule("My", h["my"], "no MY channel")
    rule("speed terms", h["speed_sweep"] or lv["VX"].size >= 2, "one speed only")
    rule("vertical", h["loaded_radius"], "no RL channel")
    rule("rolling radius", h["effective_radius"], "no RE channel")
    return out, notes
