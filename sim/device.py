"""The MuJoCo device entity."""
