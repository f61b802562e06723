"""Learning residual dynamics from flight data.

Public entry points:
    gp.sparse_gp.SparseGP, gp.exact_gp.ExactGP: estimators (fit / predict -> mean, std).
    gp.inducing.InducingConfig: low_speed / cluster / random inducing points.
    gp.features.feature_definition: velocity / state_input / history feature sets.
    gp.datasets.residual_dataset: residual datasets from flight logs.
    gp.training.train_residual_model: the library behind ``fit-gp``.
    gp.model_io.load_model / save_model / ResidualModel: model files; ResidualModel
        .casadi_function() is the NMPC's residual g(z).
    gp.local_gp.LocalGP: [Ostafew16]'s sliding local GP over experience bins.
"""
