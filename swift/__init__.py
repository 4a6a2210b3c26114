"""SWIFT: short-wavelength, intermediate-frequency tyre model on top of :mod:`mftyre`.

* :mod:`swift.road`        road profiles (flat, step, cleat, trapezoid, circular bump, sine, sampled/CSV, two-track)
* :mod:`swift.enveloping`  tandem elliptical cams -> effective road height, slope, curvature, road camber;
                           the quasi-static tyre over an obstacle (fixed axle height or constant load)
* :mod:`swift.ring`        rigid-ring equations (belt, sidewall, residual springs, contact-patch slip with the
                           Magic Formula, effective rolling radius variation over the curved effective road)
* :mod:`swift.simulate`    compiled fixed-step stepper ``step(state, inputs, dt)`` and an adaptive reference

Every modelling choice the literature leaves open is stated, with its equation, in the module docstrings.
"""
from .enveloping import Cams, CamTable, EffectiveRoad, QuasiStatic, cam_height, effective_road, effective_road_3d, \
    quasi_static, tandem_base
from .ring import INPUT_NAMES, OUTPUT_NAMES, STATE_NAMES, RingConstants
from .road import CircularBump, Cleat, Flat, Road, Sampled, Sine, Step, Trapezoid, TwoTrack
from .simulate import SimResult, StepInputs, StepSeries, SwiftTyre

__all__ = ["Road", "Flat", "Step", "Cleat", "Trapezoid", "CircularBump", "Sine", "Sampled", "TwoTrack",
           "Cams", "CamTable", "EffectiveRoad", "QuasiStatic", "cam_height", "effective_road", "effective_road_3d",
           "quasi_static", "tandem_base", "RingConstants", "STATE_NAMES", "INPUT_NAMES", "OUTPUT_NAMES",
           "SwiftTyre", "StepInputs", "StepSeries", "SimResult"]
