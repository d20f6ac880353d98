#!/usr/bin/env python3
# A copy of a scenario with its contact_solver.pressure_window set (for the mesh studies'
# --pressure-window): the key added to an existing [contact_solver] table, or the table appended.
# Refuses a scenario that sets the window itself, and a window that is not a time > 0.
#   set_pressure_window.py SCENARIO OUT TAU
import re
import sys

text, tau = open(sys.argv[1]).read(), sys.argv[3]
try:
    if not float(tau) > 0:
        raise ValueError
except ValueError:
    sys.exit(f"--pressure-window: a time > 0 in seconds, not {tau!r}")
if re.search(r"^\s*pressure_window\s*=", text, flags=re.M):
    sys.exit(f"{sys.argv[1]} sets pressure_window itself: edit it there instead of --pressure-window")
if re.search(r"^\s*\[contact_solver\]", text, flags=re.M):
    text = re.sub(r"^(\s*\[contact_solver\][^\n]*\n)", lambda m: m.group(1) + f"pressure_window = {tau}\n", text, count=1, flags=re.M)
else:
    text += f"\n[contact_solver]\npressure_window = {tau}\n"
open(sys.argv[2], "w").write(text)
