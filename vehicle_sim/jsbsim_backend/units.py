"""Unit conversions between JSBSim's English units and SI (exact definitions)."""

import math

M_PER_FT = 0.3048
M_PER_IN = 0.0254
N_PER_LBF = 4.4482216152605
KG_PER_SLUG = N_PER_LBF / M_PER_FT
RADPS_PER_RPM = 2.0 * math.pi / 60.0
