"""Benchmark parts: each module exposes ``run(progress, quick) -> dict`` of named figures."""
