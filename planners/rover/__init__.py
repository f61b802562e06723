"""Path repeating for ground robots ([Ostafew16]): taught paths, path-relative localisation,
the unicycle LB-NMPC (turn rate optimised, speed fixed to the schedule) and the
experience-based speed scheduler. The learned disturbance comes in as numbers (planners sits
below gp; experiments/rover joins the two)."""
