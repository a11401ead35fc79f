"""Calibration and inverse design: fits of inputs to measured switching angles, and
designs of rods that switch at given angles."""
