"""Simulated sensors: LeafSystems that turn the plant's state into what a real sensor reports."""
