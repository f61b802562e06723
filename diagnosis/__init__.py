"""Diagnosis: what does our simulation get wrong? (docs/design.md section 8).

Given measured flight logs and the simulation config that claims to describe the vehicle, the
diagnosis computes the force residual the config does not explain, fits one candidate model per
name of the effect vocabulary, selects causes by their error on held-out segments, measures the
gain by replaying the logged setpoints through the simulation, and writes an extended config.
"""
