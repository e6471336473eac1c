#!/usr/bin/env python3
"""Write the shipped haptic probe trace (configs/probe_trace.csv) for `tissue probe SURROGATE --trace`.

A synthetic 1 kHz device recording, 1.5 s long, at a contact point (mm) with forces (N):
  0.0-0.5 s  press along +x (into the lateral surface of the built-in lung) up to 0.8 * max_force, with a 0.3 mm,
             8 Hz hand tremor of the contact point;
  0.5-1.0 s  hold the press and drag sideways: fy = 0.3 * max_force * sin(2 pi 2 t), the point sliding 3 mm in y;
  1.0-1.3 s  release;
  1.3-1.35 s a short overshoot to 1.2 * max_force, outside the trained range (the probe flags and clamps it);
  1.35-1.5 s at rest.

    scripts/make_probe_trace.py [--point X Y Z] [--max-force F] [--out configs/probe_trace.csv]
"""
import argparse
import math


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--point", nargs=3, type=float, default=[-78.0, 0.0, 20.0], help="contact point [mm]")
    parser.add_argument("--max-force", type=float, default=0.4, help="the surrogate's trained range [N]")
    parser.add_argument("--rate", type=float, default=1000.0, help="samples per second")
    parser.add_argument("--out", default="configs/probe_trace.csv")
    a = parser.parse_args()

    rows = ["t,x,y,z,fx,fy,fz"]
    n = int(round(1.5 * a.rate))
    for i in range(n):
        t = i / a.rate
        x, y, z = a.point
        fx = fy = fz = 0.0
        tremor = 0.3 * math.sin(2 * math.pi * 8 * t)
        if t < 0.5:
            fx = 0.8 * a.max_force * t / 0.5
        elif t < 1.0:
            fx = 0.8 * a.max_force
            fy = 0.3 * a.max_force * math.sin(2 * math.pi * 2 * (t - 0.5))
            y += 3.0 * (t - 0.5) / 0.5
        elif t < 1.3:
            fx = 0.8 * a.max_force * (1.3 - t) / 0.3
            y += 3.0
        elif t < 1.35:
            fx = 1.2 * a.max_force
            y += 3.0
        else:
            y += 3.0
        rows.append(f"{t:.3f},{x + tremor:.4f},{y:.4f},{z + 0.5 * tremor:.4f},{fx:.6f},{fy:.6f},{fz:.6f}")
    with open(a.out, "w") as f:
        f.write("\n".join(rows) + "\n")
    print(f"wrote {a.out} ({n} samples)")


if __name__ == "__main__":
    main()
