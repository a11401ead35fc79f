"""Equilibria of any scene: the state under given loads, branches along any input, folds.

Which equilibrium an input set means: ``equilibrium(scene)`` is the state reached by ramping
every load from zero (the straight, unloaded rod) to its value, following the equilibrium
continuously; if the ramp meets a fold the rod snaps there, and the result is the state it
snaps to (status ``SNAPPED_WHILE_LOADING``). ``equilibrium(scene, state=x)`` is instead the
equilibrium continued from a given state (Newton from x). A branch (``branch``) starts from
the ramped equilibrium at its first value, or from a given state.
"""
