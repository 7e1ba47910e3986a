"""What paper 001's two models share (the motion generator, ``training.motion``, and the garment
regressor, ``training.garment``): the Transformer fields of their configs (``config``), a frame's
pose features and the Transformer's positions (``frames``), the store's body as a differentiable
layer (``body``) and STED (``sted``). Nothing here imports either model."""
