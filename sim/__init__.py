"""MuJoCo simulation: models built from example-robot-data URDFs, scenes, the MuJoCo device."""
