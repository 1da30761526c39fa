"""The planning core: error model along routes, reach graph, exact Pareto searches, choice.

Pure functions over numpy arrays; no file or network I/O here.
"""
