"""The rod in time: vibration modes of equilibria (``modes``)."""
