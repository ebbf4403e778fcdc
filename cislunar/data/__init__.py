"""Plain-text inputs transcribed from the papers, each file with its source in its header (read with importlib.resources).

The top-level ``data/`` of a checkout is a link to this folder, so a clone and an installed wheel read the same files.
"""
