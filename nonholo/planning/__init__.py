"""The planning core and the strategies (:func:`nonholo.plan` is the entry point).

- :mod:`nonholo.planning.core`: problem, evaluation, options, step loop, result builder;
- :mod:`nonholo.planning.strategy_paper`: strategy ``"paper"``, the appendix's algorithm;
- :mod:`nonholo.planning.strategy_robust`: strategy ``"robust"``, the default.
"""
