#!/usr/bin/env python3
"""What a real recording's longitudinal channel shows, next to a single-track nominal's motor line.

Reads a shipped real recording (the ETH CSV columns: t_nominal_s, theta_rad, vx_world_mps,
vy_world_mps, throttle_cmd; from data/real/eth_lasgroup_rccar.zip), turns the world velocity
into the body frame, differentiates v_x (central differences, 5-sample mean) and prints the median
acceleration by throttle (delayed by --lag-s, the throttle delay the diagnosis finds) and
speed, beside what the nominal's DC-motor line gives there before any traction limit:
  a = (T_stall / R) (max(u, 0) + k_brake min(u, 0) - v / v_nl) / m - c_rr g tanh(v / v_rr).
Then a least-squares line a = c_u u + c_v v + c_0 per regime, which says whether the
acceleration follows the speed (back-EMF) or not (a constant brake).

Usage: python3 scripts/real_longitudinal.py [--member train_2.csv] [--lag-s 0.2]
       [--params data/config/eth_rccar_single_track.yaml]
Needs numpy (Debian: python3-numpy).
"""
import argparse
import csv
import io
import math
import os
import zipfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_params(path):
    """The flat `key: value` lines of a single-track YAML (enough for the motor line)."""
    p = {}
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if ":" in line and not line.startswith("tyre"):
                k, v = line.split(":", 1)
                try:
                    p[k.strip()] = float(v)
                except ValueError:
                    pass
    return p


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--zip", default=os.path.join(ROOT, "data/real/eth_lasgroup_rccar.zip"))
    ap.add_argument("--member", default="train_2.csv")
    ap.add_argument("--lag-s", type=float, default=0.2)
    ap.add_argument("--params", default=os.path.join(ROOT, "data/config/eth_rccar_single_track.yaml"))
    a = ap.parse_args()

    with zipfile.ZipFile(a.zip) as z:
        name = next(n for n in z.namelist() if n.endswith(a.member))
        rows = list(csv.DictReader(io.TextIOWrapper(z.open(name), "utf-8")))
    col = lambda k: np.array([float(r[k]) for r in rows])
    t, th = col("t_nominal_s"), col("theta_rad")
    vxw, vyw, u = col("vx_world_mps"), col("vy_world_mps"), col("throttle_cmd")
    dt = float(np.median(np.diff(t)))
    vx = np.cos(th) * vxw + np.sin(th) * vyw
    ax = np.convolve(np.gradient(vx, dt), np.ones(5) / 5, "same")
    lag = int(round(a.lag_s / dt))
    ul = np.concatenate([np.full(lag, u[0]), u[:-lag]]) if lag > 0 else u

    p = read_params(a.params)
    g = p.get("gravity_mps2", 9.81)
    drive = p["stall_torque_Nm"] / p["wheel_radius_m"] / p["mass_kg"]  # [m/s^2] at u = 1, v = 0
    k_brake = p.get("brake_torque_ratio", 1.0)
    c_rr, v_rr = p.get("rolling_resistance", 0.05), p.get("rolling_resistance_speed_mps", 0.5)

    def nominal(uu, v):
        return drive * (max(uu, 0) + k_brake * min(uu, 0) - v / p["no_load_speed_mps"]) - c_rr * g * math.tanh(v / v_rr)

    print(f"{a.member}: {len(t)} rows, dt {dt:.4f} s, throttle delayed {lag * dt:.3f} s; "
          f"nominal {os.path.relpath(a.params, ROOT)}")
    u_bins = [(-1.0, -0.5), (-0.5, -0.1), (-0.1, 0.1), (0.1, 0.3), (0.3, 0.6), (0.6, 1.01)]
    v_bins = [(-5, -1), (-1, -0.3), (0.3, 1.5), (1.5, 3), (3, 6)]
    print("\nmedian measured / nominal motor line [m/s^2] (samples); columns: v_x [m/s]")
    print("| throttle | " + " | ".join(f"{lo}..{hi}" for lo, hi in v_bins) + " |")
    print("|---|" + "---|" * len(v_bins))
    for ulo, uhi in u_bins:
        cells = []
        for vlo, vhi in v_bins:
            m = (ul >= ulo) & (ul < uhi) & (vx >= vlo) & (vx < vhi)
            if m.sum() < 10:
                cells.append("-")
                continue
            nom = np.median([nominal(x, y) for x, y in zip(ul[m], vx[m])])
            cells.append(f"{np.median(ax[m]):+.1f} / {nom:+.1f} ({m.sum()})")
        print(f"| {ulo}..{uhi} | " + " | ".join(cells) + " |")

    print("\nleast squares a = c_u u + c_v v + c_0 [m/s^2] per regime:")
    for label, m in [("forward, throttle > 0.1", (vx > 0.5) & (ul > 0.1)),
                     ("forward, |throttle| < 0.1 (coasting)", (vx > 0.5) & (np.abs(ul) < 0.1)),
                     ("forward, throttle < -0.1 (braking)", (vx > 0.5) & (ul < -0.1)),
                     ("reverse, throttle < -0.1", (vx < -0.5) & (ul < -0.1))]:
        A = np.c_[ul[m], vx[m], np.ones(m.sum())]
        c = np.linalg.lstsq(A, ax[m], rcond=None)[0]
        print(f"  {label:38s} n {m.sum():5d}: c_u {c[0]:+6.2f}  c_v {c[1]:+6.2f}  c_0 {c[2]:+6.2f}")


if __name__ == "__main__":
    main()
