"""Paper 001's Transformer-CVAE body-motion generator (§3.2, §4.2): ``config`` (MotionConfig),
``model`` (MotionCVAE), ``module`` (its Lightning module: pose, vertex and KL losses), ``run``
(train, evaluate, sample)."""
