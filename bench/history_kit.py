"""Figures read from a tactus-solve history.csv, shared by the bench scripts."""
import csv


def contact_impulse(history_csv):
    """The time integral of the contact normal force over the run (trapezoid rule over the rows), N s."""
    with open(history_csv) as f:
        rows = list(csv.DictReader(f))
    t = [float(r["time"]) for r in rows]
    force = [float(r["contact_normal_force"]) for r in rows]
    return sum(0.5 * (force[i] + force[i + 1]) * (t[i + 1] - t[i]) for i in range(len(t) - 1))
