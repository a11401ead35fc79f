"""The rod in time: vibration modes of equilibria (``modes``) and the motion itself
(``integrate``)."""
