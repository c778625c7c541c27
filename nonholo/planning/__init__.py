"""The planning core and the strategies (:func:`nonholo.plan` is the entry point).

- :mod:`nonholo.planning.problem`: the problem; :mod:`nonholo.planning.settings`: its
  numerical settings and the checks of single arguments;
- :mod:`nonholo.planning.endpoint_map`: the endpoint map, its evaluations and sensitivities;
- :mod:`nonholo.planning.core`: options, the step loop of the θ-flow, what a strategy is and returns;
- :mod:`nonholo.planning.result_builder`: a run's result;
- :mod:`nonholo.planning.strategy_paper`: strategy ``"paper"``, the appendix's algorithm;
- :mod:`nonholo.planning.strategy_robust`: strategy ``"robust"``, the default;
- :mod:`nonholo.planning.route`: the global route (its paths and hops:
  :mod:`nonholo.planning.route_paths`; its smoothing: :mod:`nonholo.planning.route_smoothing`).
"""
