#!/usr/bin/env python3
"""Writes the project's own scenarios (the paper's first experiment is copied from shared/scenarios).

Run from this folder: python3 generate.py. Deterministic: the files it writes are committed.
"""
import json
import math
import os

DT = 0.001


def demo_line(start, goal, duration=1.0, n=None):
    """A constant-speed straight line (the paper's robot moves)."""
    n = n or int(round(duration / DT)) + 1
    t = [i * duration / (n - 1) for i in range(n)]
    x = [[s + (g - s) * ti / duration for s, g in zip(start, goal)] for ti in t]
    return {"t": t, "x": x}


def paper_curve():
    t = [i * DT for i in range(1001)]
    return {"t": t, "x": [[ti * math.cos(math.pi * ti), ti * math.sin(math.pi * ti)] for ti in t]}


def ellipse(id_, center, axes, exponents=None, velocity=None, rotation=None):
    o = {"id": id_, "center": center, "semi_axes": axes, "exponents": exponents or [1] * len(axes)}
    if velocity:
        o["velocity"] = velocity
    if rotation:
        o["rotation"] = rotation
    return o


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]


def write(name, scenario, path=None):
    scenario["name"] = name
    with open(path or f"{name}.json", "w") as f:
        json.dump(scenario, f, separators=(",", ":"))


def main():
    base = {"dmp": {"N": 50, "K": 1050.0, "D": None, "alpha": 4.0},
            "rollout": {"dt": DT, "duration": 1.0, "start": None, "goal": None, "tau": None},
            "point_samples": 50, "robots": [], "robot_avoidance": None}

    # The paper's second synthetic experiment: the ellipse plus a circle.
    two = [ellipse("ellipse", [-0.5, 0.7], [0.3, 0.2]), ellipse("circle", [0.15, 0.4], [0.1, 0.1])]
    for method, params in [("static_volumetric", {"A": 10.0, "eta": 1.0}),
                           ("dynamic_volumetric", {"lambda": 10.0, "beta": 2.0, "eta": 0.5}),
                           ("steering_angle", {"gamma": 20.0, "beta": 3.0})]:
        write(f"paper-two-obstacles-{method.replace('_', '-')}",
              dict(base, demonstration=paper_curve(), obstacles=two, avoidance=dict(method=method, **params)))

    # A moving obstacle crossing the paper's curve, with relative velocity.
    moving = [ellipse("walker", [-0.98, 0.53], [0.12, 0.12], velocity=[0.6, 0.0])]
    write("moving-obstacle-dynamic-volumetric",
          dict(base, demonstration=paper_curve(), obstacles=moving,
               avoidance={"method": "dynamic_volumetric", "lambda": 10.0, "beta": 2.0, "eta": 0.5}))

    # The speed target: a 3-D DMP, N = 50, ten dynamic volumetric superquadrics (some rotated, some moving),
    # RK4 at dt = 1 ms, a 2 s rollout.
    t = [i * DT for i in range(2001)]
    demo3 = {"t": t, "x": [[0.5 * ti, 0.3 * math.sin(math.pi * ti), 0.2 * ti * ti] for ti in t]}
    obstacles = []
    for k in range(10):
        s = k / 9.0 * 2.0
        c = [0.5 * s + 0.05, 0.3 * math.sin(math.pi * s) + (0.12 if k % 2 else -0.12), 0.2 * s * s]
        ex = [1, 1, 2] if k % 3 == 0 else ([2, 2, 2] if k % 3 == 1 else [1, 1, 1])
        obstacles.append(ellipse(f"o{k}", c, [0.04, 0.05, 0.06], exponents=ex, rotation=rot_z(0.3 * k),
                                 velocity=[0.0, 0.02 * (-1) ** k, 0.0]))
    write("bench-3d-ten-dynamic-volumetric",
          dict(base, dmp={"N": 50, "K": 1050.0, "D": None, "alpha": 4.0}, demonstration=demo3, obstacles=obstacles,
               rollout={"dt": DT, "duration": 2.0, "start": None, "goal": None, "tau": None},
               avoidance={"method": "dynamic_volumetric", "lambda": 10.0, "beta": 2.0, "eta": 0.5}))

    # The paper's simulated youBots: three robots on one 6-D DMP (null-weight straight lines through a common
    # crossing), walls and a cube as rounded boxes inflated by the robot's size, each robot a moving ellipse for
    # the others with relative velocity.
    size = 0.3  # half-diagonal of a youBot footprint, the inflation of the fixed obstacles
    starts = [[0.0, 0.0], [2.0, 0.0], [1.0, 1.8]]
    goals = [[2.0, 1.6], [0.0, 1.6], [1.0, -0.2]]
    demo6 = demo_line(sum(starts, []), sum(goals, []), duration=10.0, n=1001)
    robots = [{"id": f"youbot{i + 1}", "dims": [2 * i, 2 * i + 1],
               "footprint": {"semi_axes": [0.58, 0.38], "exponents": [1, 1]}} for i in range(3)]
    cube = ellipse("cube", [0.35, 0.9], [0.1 + size, 0.1 + size], exponents=[2, 2])
    write("youbots-three-dynamic",
          dict(base, dmp={"N": 50, "K": 3050.0, "D": None, "alpha": 4.0}, demonstration=demo6, obstacles=[cube],
               rollout={"dt": DT, "duration": 12.0, "start": None, "goal": None, "tau": None},
               avoidance={"method": "dynamic_volumetric", "lambda": 60.0, "beta": 2.0, "eta": 2.0},
               robots=robots,
               robot_avoidance={"method": "dynamic_volumetric", "lambda": 60.0, "beta": 2.0, "eta": 0.2}))

    # Obstacle-aware orientation (issue 16): a 0.6 m bar, held at its middle, lowered from 0.8 m above to 0.8 m
    # below the middle of two upright pegs (radius 5 cm, 0.4 m tall, axes 0.4 m apart: a 0.3 m gap), held across
    # the gap and 10 degrees off square, so that it meets both pegs. The pegs are rounded cylinders (exponents 1, 1,
    # 4) 1.5 cm wider and 2.5 cm taller than the pegs they stand for. With the tool, the terms act on 25 points
    # along the bar (the pegs inflated by its half-thickness) and turn it until it fits past the pegs; the point
    # robot, the pegs inflated by the bar's half-length as the paper does with a held object, cannot pass.
    tau = 3.0
    n = int(round(tau / 0.01)) + 1
    t = [i * tau / (n - 1) for i in range(n)]

    def min_jerk(u):
        return u * u * u * (10 + u * (-15 + 6 * u))

    start, goal = [0.0, 0.0, 0.8], [0.0, 0.0, -0.8]
    yaw = math.radians(100.0)
    across = [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]
    bar_demo = {"t": t, "x": [[s + (g - s) * min_jerk(ti / tau) for s, g in zip(start, goal)] for ti in t],
                "q": [across] * n}

    def pegs(margin):
        r, h = 0.05 + 0.015 + margin, 0.2 + 0.025 + margin
        return [ellipse(f"peg{i}", [0.0, y, 0.0], [r, r, h], exponents=[1, 1, 4]) for i, y in enumerate([-0.2, 0.2])]

    bar = dict(base, demonstration=bar_demo, rollout={"dt": DT, "duration": 3 * tau, "start": None, "goal": None,
                                                      "tau": None})
    os.makedirs("bar-through-gap", exist_ok=True)
    for method, params in [("static_volumetric", {"A": 10.0, "eta": 1.0}),
                           ("dynamic_volumetric", {"lambda": 10.0, "beta": 2.0, "eta": 0.5})]:
        kind = method.replace("_", "-")
        avoidance = dict(method=method, **params)
        write(f"bar-through-gap-tool-{kind}",
              dict(bar, obstacles=pegs(0.0), avoidance=avoidance,
                   tool={"semi_axes": [0.3, 0.01, 0.01], "exponents": [4, 4, 4], "control_points": "axis"}),
              f"bar-through-gap/tool-{kind}.json")
        write(f"bar-through-gap-point-{kind}", dict(bar, obstacles=pegs(0.3), avoidance=avoidance),
              f"bar-through-gap/point-{kind}.json")


if __name__ == "__main__":
    main()
