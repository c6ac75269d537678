#!/usr/bin/env python3
"""Issue 54, step 1b: the lab's Table 1 angles' own uncertainty from D's definition.

A lab that reads D by hand at the pile's visible base counts a one-grain skirt or not. On a cone
of the lab's size (Table 1's mass and angle, a declared bulk density) this prints atan(2H/D) with
D widened by one grain on each side, for a grain of d_max and of d_max / 2: the spread the
definition alone puts on each measured angle. H stays (a skirt does not touch the apex).

Usage: experiments/studies/d_definition_table1.py [--porosity P] > table.md
"""
import argparse
import math
import subprocess

# Table 1 (FACTS.md): sample, d_max [mm], mass [g], measured angle [deg].
TABLE1 = [(1, 2.00, 200, 33.47), (2, 3.35, 300, 34.65), (3, 5.00, 700, 36.54), (4, 8.00, 900, 37.17)]
RHO_SOLID = 2760.0  # particle density, Table 2 [kg/m3]


def cone(mass_kg, theta_deg, rho_bulk):
    """Base diameter D and height H [m] of a cone of that mass and slope."""
    volume = mass_kg / rho_bulk
    t = math.tan(math.radians(theta_deg))
    r = (3.0 * volume / (math.pi * t)) ** (1.0 / 3.0)
    return 2.0 * r, r * t


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--porosity", type=float, default=0.40,
                    help="pile porosity, declared (the paper states none) [-]")
    a = ap.parse_args()
    if not 0.2 <= a.porosity <= 0.6:
        ap.error(f"--porosity {a.porosity}: must lie in [0.2, 0.6]")
    rho_bulk = RHO_SOLID * (1.0 - a.porosity)
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                         text=True).stdout.strip() or "unknown"
    print("# Table 1: the angle a one-grain skirt moves, counted in D or not\n")
    print(f"Made by `experiments/studies/d_definition_table1.py --porosity {a.porosity}` at "
          f"{rev}: a cone of each sample's mass and measured angle, bulk density "
          f"{rho_bulk:.0f} kg/m3 (particle density 2760 kg/m3, porosity {a.porosity} declared).\n")
    print("| sample | d_max (mm) | mass (g) | lab angle (deg) | D (mm) | H (mm) "
          "| skirt of d_max: angle (deg) | change (deg) | skirt of d_max/2: angle (deg) "
          "| change (deg) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for s, dmax, m, th in TABLE1:
        d, h = cone(m / 1000.0, th, rho_bulk)
        row = [f"{s}", f"{dmax:.2f}", f"{m}", f"{th:.2f}", f"{1e3 * d:.0f}", f"{1e3 * h:.0f}"]
        for grain in (dmax, 0.5 * dmax):
            th2 = math.degrees(math.atan(2.0 * h / (d + 2.0 * grain / 1000.0)))
            row += [f"{th2:.2f}", f"{th2 - th:+.2f}"]
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
