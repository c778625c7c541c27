"""Controls: parametrisations (Fourier and Legendre series, piecewise constant), their values at the
integrator's stage times, and controls played one after another.

- :mod:`nonholo.controls.parametrisations`: :class:`Controls`, :class:`Fourier`,
  :class:`Legendre`, :class:`PiecewiseConstant`;
- :mod:`nonholo.controls.stages`: the stage tables the kernels read;
- :mod:`nonholo.controls.stitched`: :class:`~nonholo.controls.stitched.Stitched`.
"""
from .parametrisations import Controls, Fourier, Legendre, PiecewiseConstant

__all__ = ["Controls", "Fourier", "Legendre", "PiecewiseConstant"]
