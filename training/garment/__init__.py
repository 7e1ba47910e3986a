"""Paper 001's dynamic garment regressor (§3.3, §4.2): ``model`` (GarmentRegressor: a Transformer
pose encoder and an autoregressive garment decoder with a learnable BOS), ``module`` (its
Lightning module: vertex and Laplacian losses), ``run`` (train, evaluate)."""
