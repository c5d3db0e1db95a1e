"""fourws rear-wheel steering control laws (no rclpy).

``make_law(name, belief_vehicle, **options)`` builds a law (``make_loop_law`` for a loop with
a given control period); ``RearSteerActuator`` applies the rear angle and rate limits. See
:mod:`fourws_control.base` for the interface.
"""

from fourws_control.base import LawInput, Law, LinearGains, RearSteerActuator
from fourws_control.registry import LAWS, available_laws, make_law, make_loop_law
from fourws_control.signals import GAIN_UNITS, Signal

__all__ = ["GAIN_UNITS", "LAWS", "Law", "LawInput", "LinearGains", "RearSteerActuator",
           "Signal", "available_laws", "make_law", "make_loop_law"]
