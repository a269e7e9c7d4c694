"""poselifter's shipped data, installed as the package data of ``lifter.assets``: the weights and their
registry (``models.json``), the 2D error-model fits (``error_model/``) and the demo samples (``demo/``).
Read it through :mod:`lifter.assets`."""
