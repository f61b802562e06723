"""[Ostafew16] on its own robots: path-repeating LB-NMPC trials, the three experiments, and
section 3.4's illustrative example."""
