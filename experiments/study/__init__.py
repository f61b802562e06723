"""The residual-learning study: fly nominal, learn the residual, fly augmented, measure the gain.

Paper 000's experiment (random trajectories flown nominal and augmented, per inducing-point
selection) and [Ostafew16]'s trial-to-trial view (one path, refit after every trial), run in
process (lockstep, deterministic) and written up as a Markdown report with PNG plots.
"""
