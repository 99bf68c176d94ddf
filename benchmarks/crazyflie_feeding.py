"""How ``dynamics="crazyflie"`` is fed and how fast it reacts: the measurements behind the
feeding decisions of docs/crazyflie.md (no optional package needed).

    python benchmarks/crazyflie_feeding.py                   # every study (seconds)
    python benchmarks/crazyflie_feeding.py --study hover     # one of them

Studies (each prints a markdown table):

* ``hover``: a_des = 0 for 30 s with three references, every parameter set: the thrust the
  firmware's feed-forward asks for relative to the weight, altitude at 2 s and 30 s;
* ``tracking``: one Crazyflie under a PD law (the pinning gains 0.5, 1.414) tracking a circle
  of radius 1 m at 1 and 2 m/s; RMS tracking error and mean altitude error over [10, 30] s;
* ``chatter``: 20 Crazyflies under bang-bang lateral commands (+-A switched every 3 periods)
  or random directions of norm A for 10 s: crashes, largest tilt, lowest altitude;
* ``physics``: the plant at 500 Hz, 1 kHz, 2.5 kHz against 10 kHz on the 2 m/s circle;
* ``reaction``: time to 63 % of a 1 or 3 m/s^2 horizontal acceleration step, against the
  rotors' hover time constant (the safety filter's reaction time is 1.4 x it).
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402

import numpy as np  # noqa: E402

from pairflock_env import make_config  # noqa: E402
from pairflock_env.dynamics import make_vehicle  # noqa: E402
from pairflock_env.dynamics.crazyflie import CRAZYFLIE_MODELS  # noqa: E402
from pairflock_env.dynamics.crazyflie.data import FIRMWARE  # noqa: E402
from pairflock_env.dynamics.crazyflie.section import hover_rotor_time_constant  # noqa: E402

KP, KV, DT = 0.5, 1.414, 0.02


def crazyflies(n: int, z: float = 1.0, **kw):
    """A Crazyflie model of n UAVs at rest at altitude z, with its state (q, p)."""
    cfg = make_config(None, **{"dynamics": "crazyflie", "n_uavs": max(n, 2), "dt": DT, **kw})
    m = make_vehicle(cfg, 1)
    q, p = np.zeros((1, cfg.n_uavs, 3)), np.zeros((1, cfg.n_uavs, 3))
    q[..., 2] = z
    m.reset_rows(np.arange(1), q, p)
    return m, q, p


#: the references compared: the default leash, the crazyflie preset's, the anchored one
REFERENCES = {
    "integrated (leash 0.1 m, 0.3 m/s)": {},
    "integrated, leash 0.1 m, 0.1 m/s": dict(crazyflie_leash_velocity=0.1),
    "anchored": dict(crazyflie_reference="anchored"),
}


def hover() -> None:
    print("| model | reference | feed-forward / weight | z at 2 s | z at 30 s |")
    print("|---|---|---|---|---|")
    for name, a in CRAZYFLIE_MODELS.items():
        scale = 4 * a["thrust_max"] * FIRMWARE["mass_thrust"] / FIRMWARE["pwm_max"]
        for ref, kw in REFERENCES.items():
            m, q, p = crazyflies(1, crazyflie_model=name, **kw)
            z = []
            for _ in range(1500):
                m.advance(q, p, np.zeros_like(q))
                z.append(q[0, 0, 2])
            ratio = scale * a["ctrl_mass"] / a["mass"]
            print(f"| {name} | {ref} | {ratio:.3f} | {z[99]:.3f} | {z[-1]:.3f} |")


def circle(t: float, speed: float):
    """Position, velocity, acceleration on a circle of radius 1 m at 1 m altitude."""
    c, s = np.cos(speed * t), np.sin(speed * t)
    return np.array([c, s, 1.0]), speed * np.array([-s, c, 0.0]), -(speed**2) * np.array([c, s, 0])


def track(speed: float, T: float = 30.0, **kw) -> tuple[np.ndarray, float, float]:
    """The PD law on the circle (kw: the vehicle's fields; None: the ideal particle)."""
    m, q, p = crazyflies(1, **kw)
    q[0, :] = (1.0, 0.0, 1.0)
    p[0, :] = (0.0, speed, 0.0)
    m.reset_rows(np.arange(1), q, p)
    path, err, ez = [], [], []
    for k in range(round(T / DT)):
        x, v, acc = circle(k * DT, speed)
        m.advance(q, p, np.broadcast_to(acc + KP * (x - q[0]) + KV * (v - p[0]), q.shape).copy())
        assert not m.crashed.any()
        path.append(q[0, 0].copy())
        if k * DT >= 10.0:
            e = circle((k + 1) * DT, speed)[0] - q[0, 0]
            err.append(np.linalg.norm(e))
            ez.append(e[2])
    if not err:  # a flight shorter than 10 s: the path only
        return np.array(path), np.nan, np.nan
    return np.array(path), float(np.sqrt(np.mean(np.square(err)))), float(np.mean(ez))


FEEDINGS = {
    "anchored, setpoints 50 Hz": dict(crazyflie_reference="anchored"),
    "anchored, setpoints 500 Hz": dict(
        crazyflie_reference="anchored", crazyflie_setpoint_rate=500.0
    ),
    "integrated, leash 0.5 m / 1.0 m/s": dict(crazyflie_leash=0.5, crazyflie_leash_velocity=1.0),
    "integrated, leash 0.1 m / 0.3 m/s (default)": {},
    "integrated, leash 0.1 m / 0.1 m/s": dict(crazyflie_leash_velocity=0.1),
    "integrated, default, 500 Hz": dict(crazyflie_setpoint_rate=500.0),
}
MODELS = ("cf2x_L250", "cf2x_T350", "cf21B_500")


def tracking() -> None:
    for speed in (1.0, 2.0):
        print(f"{speed:g} m/s circle: tracking RMS (m) / mean altitude error (m)\n")
        print("| feeding | " + " | ".join(MODELS) + " |\n|---|" + "---|" * len(MODELS))
        for name, kw in FEEDINGS.items():
            cells = [track(speed, crazyflie_model=mod, **kw)[1:] for mod in MODELS]
            print(f"| {name} | " + " | ".join(f"{e:.3f} / {z:+.3f}" for e, z in cells) + " |")
        print()


def chatter() -> None:
    rng = np.random.default_rng(0)
    print("| reference | A (m/s^2) | pattern | crashed / 20 | max tilt (deg) | lowest z (m) |")
    print("|---|---|---|---|---|---|")
    for ref, kw in REFERENCES.items():
        for amp in (2.0, 3.0, 5.0):
            for pattern in ("switch", "random"):
                m, q, p = crazyflies(20, z=10.0, **kw)
                tilt, zmin = 0.0, 10.0
                for k in range(500):
                    if pattern == "switch":
                        a = np.zeros_like(q)
                        a[..., 0] = amp * (1 if (k // 3) % 2 else -1)
                    else:
                        a = rng.normal(0, 1, q.shape)
                        a *= amp / np.linalg.norm(a, axis=-1, keepdims=True)
                    a[..., 2] += 0.5 * (10 - q[..., 2]) - 1.4 * p[..., 2]
                    m.advance(q, p, a)
                    tilt, zmin = max(tilt, m.tilt().max()), min(zmin, q[..., 2].min())
                row = f"| {ref} | {amp:g} | {pattern} | {m.crashed.sum()} | {tilt:.1f} "
                print(row + f"| {zmin:.2f} |")


def physics() -> None:
    print("Largest distance to the 10 kHz plant over 10 s on the 2 m/s circle (m)\n")
    print("| model | 500 Hz | 1 kHz | 2.5 kHz |\n|---|---|---|---|")
    for model in CRAZYFLIE_MODELS:
        ref = track(2.0, 10.0, crazyflie_model=model, substeps=200)[0]
        runs = [track(2.0, 10.0, crazyflie_model=model, substeps=s)[0] for s in (10, 20, 50)]
        cells = [np.linalg.norm(r - ref, axis=1).max() for r in runs]
        print(f"| {model} | " + " | ".join(f"{c:.1e}" for c in cells) + " |")


def reaction() -> None:
    print("| model | rotor time constant (s) | t63 at 1 m/s^2 (s) | t63 at 3 m/s^2 (s) |")
    print("|---|---|---|---|")
    for model in CRAZYFLIE_MODELS:
        cells = []
        for amp in (1.0, 3.0):
            m, q, p = crazyflies(1, crazyflie_model=model, dt=0.002)
            for _ in range(500):
                m.advance(q, p, np.zeros_like(q))
            a = np.zeros_like(q)
            a[..., 0] = amp
            v = []
            for _ in range(500):
                m.advance(q, p, a)
                v.append(p[0, 0, 0])
            acc = np.gradient(np.array(v), 0.002)
            cells.append(0.002 * np.argmax(acc >= 0.63 * amp))
        tau = hover_rotor_time_constant(model)
        print(f"| {model} | {tau:.3f} | {cells[0]:.3f} | {cells[1]:.3f} |")


STUDIES = {"hover": hover, "tracking": tracking, "chatter": chatter, "physics": physics}
STUDIES["reaction"] = reaction


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--study", choices=list(STUDIES), nargs="+", default=list(STUDIES))
    for name in ap.parse_args(argv).study:
        print(f"\n## {name}\n")
        STUDIES[name]()


if __name__ == "__main__":
    main()
