"""Scenes: the file format, the split pipeline of Theorem 2 and the report.

It reads a scene (TOML), solves the mass centre and every effective body in its
cheapest exact form, checks the result against the unsplit multibody integration and reports.
"""
