"""Figures read from a tactus-solve history.csv, shared by the bench scripts."""
import csv

import numpy as np


def read_columns(history_csv, *names):
    """The time column and the named columns of a history, as lists of floats."""
    with open(history_csv) as f:
        rows = list(csv.DictReader(f))
    return [float(r["time"]) for r in rows], *([float(r[n]) for r in rows] for n in names)


def time_integral(t, y, lo=None, hi=None):
    """The trapezoid-rule integral of y(t) over [lo, hi] (default: the whole run), y linear between rows."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    lo = t[0] if lo is None else max(lo, t[0])
    hi = t[-1] if hi is None else min(hi, t[-1])
    inside = (t > lo) & (t < hi)
    xs = np.concatenate(([lo], t[inside], [hi]))
    return float(np.trapz(np.interp(xs, t, y), xs))


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
