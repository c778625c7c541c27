"""The planning core and the strategies (:func:`nonholo.plan` is the entry point).

- :mod:`nonholo.planning.core`: problem, evaluation, options, step loop, result builder;
- :mod:`nonholo.planning.paper`: strategy ``"paper"``, the appendix's algorithm;
- :mod:`nonholo.planning.robust`: strategy ``"robust"``, the default.
"""
