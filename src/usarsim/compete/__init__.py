"""Rescue competitions in a box: teams over a shared scenario set of varied arenas, scored from
the ground truth (the map they hand in included), and a leaderboard (docs/competitions.md)."""
