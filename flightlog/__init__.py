"""Flight logs: the schema every part shares (CSV schema v1) and its readers (CSV, PX4 ULog).

A leaf package: it imports nothing of the project, so the companion, the learning, the
diagnosis and the simulator can all read and write logs without importing each other.
"""
