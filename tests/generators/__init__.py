"""Independent generators of recorded runs (plain fixed-step RK4, written apart from the model)."""
