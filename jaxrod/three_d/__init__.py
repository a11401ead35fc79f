"""Three dimensions: out-of-plane stability of planar states and magnet tracks off the
plane."""
