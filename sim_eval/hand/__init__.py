"""Hands in the simulation: a hand attached to a scene, fitted to a grasp, closed on the object."""
