"""Figures read from a tactus-solve history.csv, shared by the bench scripts."""
import bisect
import csv


def read_columns(history_csv, *names):
    """The time column and the named columns of a history, as lists of floats."""
    with open(history_csv) as f:
        rows = list(csv.DictReader(f))
    return [float(r["time"]) for r in rows], *([float(r[n]) for r in rows] for n in names)


def time_integral(t, y, lo=None, hi=None):
    """The trapezoid-rule integral of y(t) over [lo, hi] (default: the whole run), y linear between rows."""
    lo = t[0] if lo is None else max(lo, t[0])
    hi = t[-1] if hi is None else min(hi, t[-1])
    def at(x):
        i = min(max(bisect.bisect_right(t, x) - 1, 0), len(t) - 2)
        return y[i] + (y[i + 1] - y[i]) * (x - t[i]) / (t[i + 1] - t[i])
    i0, i1 = bisect.bisect_right(t, lo), bisect.bisect_left(t, hi)
    xs = [lo] + t[i0:i1] + [hi]
    ys = [at(lo)] + y[i0:i1] + [at(hi)]
    return sum(0.5 * (ys[i] + ys[i + 1]) * (xs[i + 1] - xs[i]) for i in range(len(xs) - 1))


def contact_impulse(history_csv):
    """The time integral of the contact normal force over the run (trapezoid rule over the rows), N s."""
    t, force = read_columns(history_csv, "contact_normal_force")
    return time_integral(t, force)


def centred_mean(t, y, times, half_width):
    """The mean of y(t) over [c - half_width, c + half_width] (clipped to the run) at each time c."""
    out = []
    for c in times:
        lo, hi = max(c - half_width, t[0]), min(c + half_width, t[-1])
        out.append(time_integral(t, y, lo, hi) / (hi - lo))
    return out
