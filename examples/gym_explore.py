"""A Gymnasium episode in the simulator: usarsim/Explore-v0 with a random policy (replace it with
yours).  Prints the return and the floor the robot saw.

    python examples/gym_explore.py --steps 200
    python examples/gym_explore.py --steps 200 --transport inproc   # the simulator in this process
"""

from __future__ import annotations

import argparse

import gymnasium

import usarsim.envs  # noqa: F401  (registers usarsim/Explore-v0)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=200, help="steps of 0.1 s (default 200)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument(
        "--transport",
        choices=("tcp", "inproc"),
        default="tcp",
        help="tcp: a usarsim serve process (default); inproc: the simulator in this process, "
        "the same episode several times faster",
    )
    args = ap.parse_args()
    env = gymnasium.make("usarsim/Explore-v0", transport=args.transport)
    try:
        obs, info = env.reset(seed=args.seed)
        env.action_space.seed(args.seed)
        total = 0.0
        for _ in range(args.steps):
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            total += float(reward)
            if terminated or truncated:
                break
        print(f"return {total:.1f} over {args.steps} steps; info: {info}")
    finally:
        env.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
