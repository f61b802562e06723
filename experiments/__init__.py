"""Experiments that use every part below them: the study, the demo, the showcase, benchmarks."""
