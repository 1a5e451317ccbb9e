"""The overhead camera: frame sources, marker detection, floor calibration, the lens model and the
pose tracker the loop reads."""
