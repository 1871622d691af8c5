"""Scenes: the file format, the split pipeline of Theorem 2, the report and the command line.

The top layer: it reads a scene (TOML), solves the mass centre and every effective body in its
cheapest exact form, checks the result against the unsplit multibody integration and reports.
"""
