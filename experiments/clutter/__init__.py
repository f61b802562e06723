"""[Kulathunga23]'s Table 3 in our simulator: goal reaching in a seeded random forest."""
