# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
r"""Nonlinear 8-DOF spread-tire vehicle model (Samsundar 1996, ch. 8, eqs. 8.1-8.51; re-derived).

Degrees of freedom: longitudinal U, lateral V, yaw r, sprung-mass roll :math:`\phi` (angle and
rate p), the spin :math:`\omega_i` of each of the four wheels; plus the earth-frame pose
(X, Y, heading :math:`\psi`), two load-transfer acceleration states and four tire-lag states.
Axes are ISO 8855 / REP-103 (x forward, y left, z up; r and steer positive to the left;
:math:`\phi` positive right side down, so a left turn rolls the body to :math:`\phi > 0`).
The paper's chapter 8 uses SAE-like signs (its roll angle is negative in a positive turn,
Figure 8.6); every equation below is re-derived in fourws axes.

Equations of motion
-------------------
The sprung mass :math:`m_s` (CG a height h above the roll axis, at the longitudinal position of
the total CG) rolls about a body-fixed roll axis; the unsprung mass moves with the yawing frame.
Velocity of the sprung CG in the yawing frame is :math:`(U + r h \sin\phi,\;
V - h p\cos\phi)`, which gives (:math:`c = \cos\phi`, :math:`s = \sin\phi`)

.. math::

    m(\dot U - V r) + m_s h (s\,\dot r + 2 r p c) &= \textstyle\sum F_x \\
    m(\dot V + U r) - m_s h c\,\dot p + m_s h s (p^2 + r^2) &= \textstyle\sum F_y \\
    I_z \dot r - I_{xz} \dot p &= \textstyle\sum N \\
    I_x \dot p - I_{xz} \dot r - m_s h c (\dot V + U r)
        &= m_s g h s - (K_{\phi f} + K_{\phi r})\phi - (C_{\phi f} + C_{\phi r}) p

(eqs. 8.1-8.4 and 8.14; the paper linearizes the trigonometric terms and writes a single
Coriolis term). :math:`I_x` is about the roll axis, as in the 3-DOF model (ch. 6), so the
linearized V-r-phi block is exactly ``fourws_sim.models.roll3dof``. The symmetric 3x3 system
in :math:`\dot V, \dot r, \dot p` is solved in closed form, then :math:`\dot U`.
Pose: :math:`\dot X = U\cos\psi - V\sin\psi`, :math:`\dot Y = U\sin\psi + V\cos\psi`,
:math:`\dot\psi = r` (eqs. 8.15-8.17).

Wheels (eqs. 8.5-8.8): :math:`I_w \dot\omega_i = T_{o,i} + T_{f,i}` with
:math:`T_{o,i} = T_{d,i} - R F_{x,i}` (drive torque and tire force) and the friction torque
of brake plus rolling resistance, capacity :math:`T_{c,i} = T_{b,i} + f_r F_{z,i} R`, in a
stick-slip form that a fixed step integrates without chatter (Karnopp's friction model with a
stuck band and a continuous stick law):

* sliding, :math:`I_w|\omega_i| \ge T_c \tau_b`:
  :math:`I_w\dot\omega_i = T_o - \mathrm{sign}(\omega_i) T_c` (Coulomb friction);
* stuck band, :math:`I_w|\omega_i| < T_c \tau_b`, with :math:`|T_o| \le T_c`: held,
  :math:`\dot\omega_i = -(\omega_i/\tau_b)(1 - |T_o|/T_c)` -- the spin decays to zero (down to
  :data:`HELD_SPIN_FLOOR_RADPS`, never through it): a brake cannot spin a wheel backwards,
  a locked wheel stays locked, a braked car at rest does not creep under a smaller drive
  torque;
* stuck band with :math:`|T_o| > T_c`: breaking loose,
  :math:`I_w\dot\omega_i = T_o - \mathrm{sign}(T_o) T_c`. The factor :math:`1 - |T_o|/T_c`
  (the friction reserve) makes the two continuous at :math:`|T_o| = T_c`, so a wheel at the
  breakaway threshold does not chatter between holding and slipping.

:math:`\tau_b` = :data:`BRAKE_HOLD_TIME_S`. With :math:`T_c = 0` it is the free wheel.

Geometry (eqs. 8.32-8.50)
-------------------------
Road-wheel angles: :math:`\delta_{f} = \delta_{f,cmd} + \varepsilon_f\phi`,
:math:`\delta_{r} = \delta_{r,cmd} + \varepsilon_r\phi` (8.32/8.33); the front command is the
steering-wheel angle over the steering ratio (:func:`road_wheel_angle`). Wheel i at
:math:`(x_i, y_i)` = FL (a, T_f/2), FR (a, -T_f/2), RL (-b, T_r/2), RR (-b, -T_r/2) has the
centre velocity :math:`(U - r y_i, V + r x_i)` (8.34-8.38), rotated by the road-wheel angle
into the wheel frame :math:`(v_x, v_y)`. Slip angle and slip ratio (8.39-8.46) with a
denominator regularized at standstill only (:data:`V_MIN_DEFAULT_MPS` = 1 m/s, the same for
every vehicle and step):

.. math::

    \alpha_i = \operatorname{atan2}(v_{y,i}, \max(|v_{x,i}|, v_{min})), \qquad
    \kappa_i = \frac{\omega_i R - v_{x,i}}{\max(|v_{x,i}|, v_{min})}.

Above :math:`v_{min}` both are the exact kinematic slips. At rest both are exactly 0, so a car
at rest with no input stays at rest; below :math:`v_{min}` the tires act as stiff viscous
dampers, which brings the car to rest smoothly. The price: a tire has no static friction, so a
car held only by locked wheels against a force F per tire creeps at :math:`F v_{min}/C_s`
(7 cm/s for 1.4 kN on table_8_1's front tires; a car held by the brakes of its driven wheels
does not move at all).

Stiff, light wheels (sub-steps)
-------------------------------
Linearized about free rolling, a wheel's spin relative to the road relaxes with the rate
:math:`\lambda_i = R^2 C_s / (I_w \max(|v_{x,i}|, v_{min}))` (1/s; :math:`C_s` the tire's
longitudinal slip stiffness), which grows without bound for light wheels and at low speed
(table_8_1's tires with :math:`I_w` = 0.01 kg m^2: about 1e5 1/s at 2 m/s). A fixed-step
integrator is stable only for :math:`\lambda\,dt` below a bound, so the compiled RK4 and
Euler loops split a step into as many equal sub-steps as the fastest slip mode of the current
state needs (:func:`substeps`): the slips keep their exact definition and the physics does not
depend on the step. The rate (``Aux.slip_rate_per_s``) is the largest over the four wheels of
:math:`K_{spin}/\max(|v_x|, v_{min})` (``PARAM.K_SPIN`` = :math:`R^2 C_s / I_w` of the
stiffest tire at :data:`SPIN_LOAD_FACTOR` x its static load) and of the tire-lag rate
:math:`\max(|v_x|, v_{min})/\sigma`. Where a step would need more than :data:`MAX_SUBSTEPS`
sub-steps even at standstill, :func:`check_step` (called by the simulator) refuses the step
and the wheel inertia with a one-line error.

Tire forces :math:`(F_x, F_y, M_z)` come from the vehicle's tire model in the wheel frame and
are rotated by the road-wheel angle into the body frame; aligning moments add to the yaw
moment. With a relaxation length :math:`\sigma > 0` (per axle:
``tire.relaxation_length_front_m``, ``tire.relaxation_length_rear_m``) the tire sees a lagged
slip angle,
:math:`\dot\alpha_{l,i} = (\max(|v_{x,i}|, v_{min})/\sigma)(\alpha_i - \alpha_{l,i})`
(first-order stretched-string lag, ch. 5); where :math:`\sigma = 0` the axle's two lag
states are inert and its tires see :math:`\alpha_i`.

Normal loads (Figures 8.3/8.4, eqs. 8.18-8.31)
----------------------------------------------
Static :math:`mgb/2L` front, :math:`mga/2L` rear per tire; longitudinal transfer
:math:`m a_x h_{cg} / L` from front to rear axle; lateral transfer on axle i (to the right
wheel, from the left)

.. math::

    \Delta F_{z,i} = \frac{K_{\phi i}\phi + C_{\phi i} p + m_i\,(m_s/m)\,h_{rc,i}\,a_y
                     + m_i\,(m_u/m)\,h_u\,a_y}{T_i},

with :math:`m_i` the axle's share of the mass (:math:`mb/L` front) — the suspension roll
moment plus the load carried through the roll centre and the unsprung mass. In a steady turn
this equals the paper's moment balance (8.22-8.27). The accelerations :math:`a_x, a_y` used
here are first-order lagged copies of :math:`\dot U - V r` and :math:`\dot V + U r`
(time constant :data:`LOAD_TRANSFER_TIME_S`): this stands in for the pitch/heave dynamics the
model leaves out and removes the algebraic loop between loads, tire forces and accelerations.
Loads are clamped at 0 (a lifted wheel has no force).

Rolling resistance (``tire.rolling_resistance`` :math:`f_r`, default 0) is a torque
:math:`f_r F_z R` opposing wheel spin (part of the stick-slip friction torque above).

Aerodynamic drag and lift (``aero``, :class:`fourws_sim.params.Aero`; absent = none)
-----------------------------------------------------------------------------------
Still air: the air speed is U. The drag :math:`D = \tfrac12\rho C_d A\,U|U|` acts on the
body along -x, at the height of the CG, so it adds :math:`-D` to :math:`\sum F_x` and no
moment about the CG. The longitudinal load transfer is the moment of the forces at the ground
about the CG, and those sum to :math:`m a_x + D`, so it is :math:`(m a_x + D) h_{cg}/L`
(coasting on drag alone transfers no load; drag at the ground would transfer
:math:`D h_{cg}/L` to the front). The lift :math:`\tfrac12\rho C_{l,i} A\,U^2` of axle i
(front, rear; negative = downforce) is taken off its static load, half from each wheel,
before the transfers. Side force and aerodynamic yaw, pitch and roll moments are left out.
With ``aero`` absent the three parameters are 0 and every result is that of the model
without them, bit for bit (``test_bit_identical``).

Differentials (``driveline``, :class:`fourws_sim.params.Driveline`; absent = open)
--------------------------------------------------------------------------------
The drive torque inputs are what the driveline gives each axle's differential, split equally
between its wheels (``T_l = T_r = T_axle/2``: an open differential, what the speed-hold
driver sends). The differential moves a locking torque from the faster to the slower wheel,

.. math::

    T_{lock} = c_v(\omega_l - \omega_r) + \tfrac12 k_b\,|T_l + T_r|\,
               \mathrm{sat}\big((\omega_l - \omega_r)/\Delta\omega_b\big), \qquad
    T_l' = T_l - T_{lock}, \quad T_r' = T_r + T_{lock},

with the viscous coupling :math:`c_v` (N m s/rad) and :math:`k_b = (TBR - 1)/(TBR + 1)` of
the torque bias ratio (at full bias the slower wheel gets TBR times the faster one's
torque), :math:`\Delta\omega_b` = :data:`BIAS_BAND_RADPS`. A locked differential is the
coupling :math:`c_v = I_w/(2\tau_l)` (:data:`LOCK_TIME_S`): the wheels' speed difference
decays with :math:`\tau_l`. The gears' inertia is left out. The coupling's rate
:math:`(2c_v + k_b|T|/\Delta\omega_b)/I_w` joins the sub-step rates. The yaw moment of a
locking torque on an axle of track T through the tire forces (at steady spin) is
:math:`T\,T_{lock}/R`: positive (to the left) when the left wheel spins faster.

Free steering system (model ``8dof-free``)
------------------------------------------
With fixed steering control (model ``8dof``, the paper's ch. 8) the front command is an input
and the two steering states ``DELTA_S``, ``DELTA_S_RATE`` stay 0 (derivatives exactly 0: the
results are those of the model without them). With free control (``params_for(...,
free_steering=True)``, model ``8dof-free``) the front road-wheel angle is the state
:math:`\delta_s` of a steering system: both front wheels turn about their kingpins, rigidly
linked to the steering wheel through the steering ratio N (:math:`\delta_H = N\delta_s`; no
column or rack compliance), and the input ``DELTA_F`` is not used. Re-derived for fourws from
the paper's free-control model (eq. 3.18/4.53, after Whitehead) with the inertia it leaves out
(it assumes the system "highly damped", so first order):

.. math::

    J\,\ddot\delta_s = N T_H + \sum_{i = FL, FR} \left(M_{z,i} - e\,F_{y,i}\right)
        - \nu\,\dot\delta_s - T_{fric},
    \qquad \delta_f = \delta_s + \varepsilon_f\phi .

:math:`J` is the inertia of the system about the kingpins (wheels, tie rods, rack, plus
:math:`N^2` times the steering wheel and column: the kinetic energy
:math:`\tfrac12 J\dot\delta_s^2`), :math:`T_H` the driver's torque on the steering wheel
(input ``STEER_TORQUE``; its virtual work on :math:`\delta_H = N\delta_s` makes it
:math:`N T_H` about the kingpins), :math:`\nu` the viscous damping about the kingpins (the
paper's :math:`\nu`). The returning torque of each front tire: its tire-frame lateral force
acts at the contact centre, the caster trail :math:`e` behind the point where the kingpin axis
meets the ground, so its moment about the kingpin (z up) is :math:`-e F_y` -- a force to the
left behind the axis turns the wheel to the right; the tire's aligning moment :math:`M_z`
(pneumatic trail, from the tire model) adds. Left out, as in the paper: kingpin inclination
and the caster's weight-lift torque, the moments of the longitudinal forces on the scrub
radius, the wheels' gyroscopic torques. The Coulomb friction :math:`T_{fric}` of capacity
:math:`T_c` (rack, column) takes the stick-slip form of the wheels above (stuck band
:math:`J|\dot\delta_s| < T_c\tau_b`). For :math:`J \to 0`, :math:`T_c = 0` and a tire without
aligning moment this is eq. 4.53, :math:`\nu\dot\delta_f = T_f - \eta F_{yf}`, with
:math:`T_f = N T_H`, :math:`\eta = e` and :math:`F_{yf}` the front axle's force
(:mod:`fourws_sim.models.free2dof`). Parameters: ``steering.inertia_kgm2``,
``damping_nms_per_rad``, ``trail_m`` (in the 8-DOF the caster trail only: the tire model gives
the pneumatic trail), ``coulomb_friction_nm``, ``ratio``. The sub-step rate includes the
system's fastest rate (``PARAM.RATE_S``: :math:`\nu/J`, :math:`\sqrt{k/J}` with the returning
stiffness :math:`k = 2(\partial M_z/\partial\alpha - e\,\partial F_y/\partial\alpha)` of the
front tires at their static load, and :math:`1/\tau_b` with friction).

Two implementations. :func:`kernels_for` gives the numba-compiled right-hand side and
fixed-step integrator loops for one tire model: the equations are written once there, as
branch-free functions of plain numbers that the simulator's scalar kernel and the study's
kernel of many points at once both call (:mod:`fourws_sim.models.eightdof_kernels`); every
simulation, study point and linearization runs them. :func:`evaluate` (:func:`derivatives`) is
the readable NumPy reference, the test oracle (``test/test_eightdof.py`` checks they agree to
round-off) and the right-hand side of the ``solve_ivp`` reference integrator. It stays a
separate implementation: the branch-free form computes both sides of every choice and divides
by zero on the side not taken (a wheel without friction capacity), which IEEE arithmetic in
compiled code allows and plain Python does not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from types import ModuleType
from typing import Any, Callable, NamedTuple

import numpy as np

from fourws_sim import variants
from fourws_sim.errors import ParameterError
from fourws_sim.params import GRAVITY_MPS2, Vehicle
from fourws_sim.tires import get_tire


class STATE(IntEnum):
    """State components of the 8-DOF model (SI units)."""

    U = 0  #: longitudinal velocity of the CG, body frame, m/s
    V = 1  #: lateral velocity of the CG, body frame, m/s (positive left)
    R = 2  #: yaw rate, rad/s (positive left)
    PHI = 3  #: sprung-mass roll angle, rad (positive right side down)
    P = 4  #: roll rate, rad/s
    OMEGA_FL = 5  #: wheel spin front left, rad/s (positive rolling forward)
    OMEGA_FR = 6  #: wheel spin front right, rad/s
    OMEGA_RL = 7  #: wheel spin rear left, rad/s
    OMEGA_RR = 8  #: wheel spin rear right, rad/s
    X = 9  #: earth-frame x of the CG, m
    Y = 10  #: earth-frame y of the CG, m
    PSI = 11  #: heading, rad
    AX_LT = 12  #: lagged longitudinal acceleration used for load transfer, m/s^2
    AY_LT = 13  #: lagged lateral acceleration used for load transfer, m/s^2
    ALPHA_FL = 14  #: lagged slip angle front left (relaxation length), rad
    ALPHA_FR = 15  #: lagged slip angle front right, rad
    ALPHA_RL = 16  #: lagged slip angle rear left, rad
    ALPHA_RR = 17  #: lagged slip angle rear right, rad
    DELTA_S = 18  #: front road-wheel angle of the free steering system (8dof-free), rad
    DELTA_S_RATE = 19  #: its rate, rad/s (both stay 0 with fixed steering control)


class INPUT(IntEnum):
    """Input components of the 8-DOF model (SI units)."""

    DELTA_F = 0  #: commanded front road-wheel angle (steering-wheel angle / ratio), rad
    #: (fixed steering control; unused by the free steering system)
    DELTA_R = 1  #: commanded rear road-wheel angle, rad
    STEER_TORQUE = 2  #: driver torque on the steering wheel, N m (free steering system only)
    DRIVE_FL = 3  #: drive torque front left, N m (positive forward)
    DRIVE_FR = 4  #: drive torque front right, N m
    DRIVE_RL = 5  #: drive torque rear left, N m
    DRIVE_RR = 6  #: drive torque rear right, N m
    BRAKE_FL = 7  #: brake torque front left, N m (>= 0, opposes spin)
    BRAKE_FR = 8  #: brake torque front right, N m
    BRAKE_RL = 9  #: brake torque rear left, N m
    BRAKE_RR = 10  #: brake torque rear right, N m


class PARAM(IntEnum):
    """Slots of the packed float64 parameter array used by the compiled kernels."""

    M = 0  #: total mass, kg
    MS = 1  #: sprung mass, kg
    IZ = 2  #: yaw inertia, kg m^2
    IX = 3  #: roll inertia of the sprung mass about the roll axis, kg m^2
    IXZ = 4  #: roll-yaw product of inertia, kg m^2
    A = 5  #: CG to front axle, m
    B = 6  #: CG to rear axle, m
    TF = 7  #: front track, m
    TR = 8  #: rear track, m
    H_CG = 9  #: total CG height, m
    H_ROLL = 10  #: sprung CG above the roll axis, m
    H_RC_F = 11  #: front roll-centre height, m
    H_RC_R = 12  #: rear roll-centre height, m
    H_U = 13  #: unsprung CG height, m
    R_W = 14  #: wheel radius, m
    I_W = 15  #: wheel spin inertia, kg m^2
    K_PHI_F = 16  #: front roll stiffness, N m/rad
    K_PHI_R = 17  #: rear roll stiffness, N m/rad
    C_PHI_F = 18  #: front roll damping, N m s/rad
    C_PHI_R = 19  #: rear roll damping, N m s/rad
    EPS_F = 20  #: front roll steer, rad/rad
    EPS_R = 21  #: rear roll steer, rad/rad
    MU = 22  #: road friction passed to the tire model
    F_RR = 23  #: rolling-resistance coefficient
    SIGMA_F = 24  #: relaxation length of a front tire, m (0 = no lag)
    SIGMA_R = 25  #: relaxation length of a rear tire, m (0 = no lag)
    V_MIN = 26  #: slip-denominator floor (standstill), m/s
    TAU_LT = 27  #: load-transfer lag, s
    TAU_B = 28  #: brake hold time constant, s
    G = 29  #: gravity, m/s^2
    K_SPIN = 30  #: wheel-spin slip stiffness R^2 C_s / I_w (rate x slip denominator), m/s^2
    STEER_FREE = 31  #: 1.0: the free steering system drives the front angle; 0.0: fixed control
    J_S = 32  #: steering-system inertia about the kingpins (road-wheel level), kg m^2
    NU_S = 33  #: steering viscous damping about the kingpins, N m s/rad
    E_S = 34  #: caster (mechanical) trail, m
    TC_S = 35  #: steering Coulomb friction about the kingpins, N m
    N_S = 36  #: steering ratio (steering-wheel angle per road-wheel angle)
    RATE_S = 37  #: fastest steering-system rate, 1/s (sub-steps; 0 with fixed control)
    DRAG = 38  #: aerodynamic drag per U|U|, 0.5 rho C_d A, kg/m (0 = no drag)
    LIFT_F = 39  #: aerodynamic lift of one front wheel per U^2, 0.25 rho C_l,f A, kg/m
    LIFT_R = 40  #: aerodynamic lift of one rear wheel per U^2, 0.25 rho C_l,r A, kg/m
    VISC_F = 41  #: front differential's viscous coupling, N m s/rad (0 = open)
    VISC_R = 42  #: rear differential's viscous coupling, N m s/rad
    BIAS_F = 43  #: front differential's bias, (TBR - 1)/(TBR + 1) (0 = open)
    BIAS_R = 44  #: rear differential's bias


N_STATE = len(STATE)
N_INPUT = len(INPUT)
N_PARAM = len(PARAM)

#: Wheel names in fourws order.
WHEELS = ("FL", "FR", "RL", "RR")

#: Lag of the accelerations that drive load transfer, s. Short against the handling time
#: scales (yaw/roll ~0.1-1 s) and long against the 1 ms step (RK4-stable for steps < ~25 ms).
LOAD_TRANSFER_TIME_S = 0.01
#: Time constant with which a held (braked, stuck) wheel's spin decays to zero, s. RK4 is
#: stable with it for steps up to ~5 ms; it also sets the stuck band |omega| < T_c tau_b/I_w.
BRAKE_HOLD_TIME_S = 2.0e-3
#: Spin below which a held wheel counts as locked and stops decaying, rad/s (3e-10 m/s at the
#: rim). Without it the exponential decay runs into subnormal numbers after ~1.5 s of lock,
#: which are slow on x86 CPUs.
HELD_SPIN_FLOOR_RADPS = 1.0e-9
#: Smallest slip denominator, m/s: regularizes both slips at standstill only (a walking-pace
#: floor, below which the tires act as viscous dampers).
V_MIN_DEFAULT_MPS = 1.0
#: Normal load, as a multiple of the static load of the more loaded axle's tires, at which
#: ``PARAM.K_SPIN`` takes the tire's longitudinal slip stiffness (load transfer in hard
#: braking or cornering; the rate bounds below leave room above it).
SPIN_LOAD_FACTOR = 1.5
#: Largest |lambda h| of a sub-step h for the fastest slip mode lambda: RK4's stability
#: interval on the negative real axis is 2.785, explicit Euler's 2; the bounds keep a factor
#: of 1.9 and 2 for loads beyond SPIN_LOAD_FACTOR and for the wheel's coupling to the body.
RK4_RATE_BOUND = 1.5
EULER_RATE_BOUND = 1.0
#: Most sub-steps a step may take; a vehicle and step that would need more at standstill are
#: refused by :func:`check_step` (the simulation would run 1000 times slower than at 1 ms).
MAX_SUBSTEPS = 1000

#: Wheel speed difference over which a torque-bias differential's locking torque builds up
#: to its full value, rad/s (0.15 m/s at a 0.29 m rim): a smooth onset, so the locking
#: torque does not chatter when the two wheels turn at nearly the same speed.
BIAS_BAND_RADPS = 0.5
#: Time constant with which a locked differential holds its two wheels together, s: a
#: coupling of I_w / (2 LOCK_TIME_S) between the half shafts (1000 N m per rad/s of slip for
#: table_8_1's wheels; RK4 at 1 ms takes its rate 1/LOCK_TIME_S without sub-steps).
LOCK_TIME_S = 1.0e-3

# Output slots of the per-call auxiliary array (filled by the kernels, used by outputs()).
_AUX_FZ = 0
_AUX_ALPHA = 4
_AUX_KAPPA = 8
_AUX_FX = 12
_AUX_FY = 16
_AUX_MZ = 20
_AUX_DELTA_F = 24
_AUX_DELTA_R = 25
_AUX_AX = 26
_AUX_AY = 27
_AUX_RATE = 28
_AUX_DRIVE = 29
N_AUX = 33


class Aux(NamedTuple):
    """Per-wheel quantities computed alongside the derivative (arrays in order FL, FR, RL, RR).

    Attributes
    ----------
    fz_n, alpha_rad, kappa, fx_n, fy_n, mz_nm : numpy.ndarray
        Normal load (N), slip angle seen by the tire (rad), slip ratio, tire-frame
        longitudinal and lateral force (N), aligning moment (N m).
    delta_f_rad, delta_r_rad : float
        Road-wheel angles actually applied (command plus roll steer), rad.
    ax_mps2, ay_mps2 : float
        Acceleration of the CG, :math:`\\dot U - V r` and :math:`\\dot V + U r`, m/s^2.
    slip_rate_per_s : float
        Rate of the fastest slip mode (wheel spin or tire lag) at this state, 1/s: sets the
        number of sub-steps of a step (:func:`substeps`).
    drive_nm : numpy.ndarray
        Drive torque each wheel gets from its axle's differential, N m.
    """

    fz_n: np.ndarray
    alpha_rad: np.ndarray
    kappa: np.ndarray
    fx_n: np.ndarray
    fy_n: np.ndarray
    mz_nm: np.ndarray
    delta_f_rad: float
    delta_r_rad: float
    ax_mps2: float
    ay_mps2: float
    slip_rate_per_s: float
    drive_nm: np.ndarray


@dataclass(frozen=True)
class Params:
    """Parameters of the 8-DOF model.

    Attributes
    ----------
    arr : numpy.ndarray
        Packed float64 parameters, slots named by :class:`PARAM` (SI units).
    coeffs_front, coeffs_rear : numpy.ndarray
        Tire coefficient arrays of one front and one rear tire (the tire module's ``pack``).
    tire_name : str
        Tire model name (key of ``fourws_sim.tires.TIRES``).
    tire : module
        The tire module (its ``forces`` is called by :func:`derivatives`).
    steering_ratio : float
        Steering-wheel angle per front road-wheel angle (1.0 when the vehicle has none).
    """

    arr: np.ndarray
    coeffs_front: np.ndarray
    coeffs_rear: np.ndarray
    tire_name: str
    tire: ModuleType
    steering_ratio: float

    def __getitem__(self, key: PARAM) -> float:
        return float(self.arr[key])

    @property
    def free_steering(self) -> bool:
        """The free steering system drives the front angle (model ``8dof-free``)."""
        return bool(self.arr[PARAM.STEER_FREE] > 0.0)


def road_wheel_angle(steering_wheel_angle_rad: float, vehicle: Vehicle) -> float:
    """Front road-wheel angle in rad from the steering-wheel angle in rad (eq. 8.32).

    ``delta_f = delta_sw / K_sr`` with the steering ratio ``steering.ratio`` (Table 8.1:
    16.3). The roll-steer part of eq. 8.32 is added inside the model.

    Raises
    ------
    ParameterError
        If the vehicle has no ``steering`` subsystem.
    """
    vehicle.require("steering", user="road_wheel_angle")
    return float(steering_wheel_angle_rad) / vehicle.steering.ratio  # type: ignore[union-attr]


def steering_wheel_angle(road_wheel_angle_rad: float, vehicle: Vehicle) -> float:
    """Steering-wheel angle in rad for a front road-wheel angle in rad (inverse of
    :func:`road_wheel_angle`)."""
    vehicle.require("steering", user="steering_wheel_angle")
    return float(road_wheel_angle_rad) * vehicle.steering.ratio  # type: ignore[union-attr]


def _tire_module(vehicle: Vehicle, tire: str | None) -> tuple[str, ModuleType]:
    name = tire if tire is not None else (vehicle.tire.model if vehicle.tire else "linear")
    return name, get_tire(name)


def params_for(vehicle: Vehicle, tire: str | None = None, *,
               v_min_mps: float | None = None, free_steering: bool = False) -> Params:
    """Build the 8-DOF parameters of ``vehicle``.

    Parameters
    ----------
    vehicle : Vehicle
        Needs ``roll`` and ``body`` (and optionally ``tire``, ``steering``).
    tire : str, optional
        Tire model name overriding ``vehicle.tire.model`` (``linear`` when it has none).
    v_min_mps : float, optional
        Slip-denominator floor in m/s (default :data:`V_MIN_DEFAULT_MPS`): the speed below
        which both slips are regularized. It does not depend on the wheels or the step (a
        stiff wheel is integrated in sub-steps instead, see the module docstring).
    free_steering : bool
        The free steering system drives the front angle (model ``8dof-free``; needs
        ``steering`` with ``inertia_kgm2 > 0``); False: fixed control, the steering states
        stay 0.

    Raises
    ------
    ParameterError
        If ``roll`` or ``body`` is missing, ``v_min_mps`` is not finite and > 0, or (free
        steering) ``steering`` is missing or its inertia is 0.
    UnknownNameError
        If the tire model name is unknown.
    """
    vehicle.require("roll", "body", user="8dof model")
    tire_name, module = _tire_module(vehicle, tire)
    c, rl, bd = vehicle.chassis, vehicle.roll, vehicle.body
    assert rl is not None and bd is not None
    tr = vehicle.tire
    coeffs_f = np.ascontiguousarray(module.pack(vehicle, "front"), dtype=np.float64)
    coeffs_r = np.ascontiguousarray(module.pack(vehicle, "rear"), dtype=np.float64)
    if rl.sprung_mass_kg > c.mass_kg:
        raise ParameterError("roll.sprung_mass_kg", "must not exceed chassis.mass_kg",
                             vehicle.source or vehicle.name)
    arr = np.zeros(N_PARAM)
    P = PARAM
    arr[P.M] = c.mass_kg
    arr[P.MS] = rl.sprung_mass_kg
    arr[P.IZ] = c.yaw_inertia_kgm2
    arr[P.IX] = rl.roll_inertia_kgm2
    arr[P.IXZ] = rl.roll_yaw_product_kgm2
    arr[P.A] = c.cg_to_front_axle_m
    arr[P.B] = c.cg_to_rear_axle_m
    arr[P.TF] = bd.track_front_m
    arr[P.TR] = bd.track_rear_m
    arr[P.H_CG] = bd.cg_height_m
    arr[P.H_ROLL] = rl.roll_arm_m
    arr[P.H_RC_F] = bd.roll_centre_height_front_m
    arr[P.H_RC_R] = bd.roll_centre_height_rear_m
    arr[P.H_U] = bd.unsprung_cg_height_m
    arr[P.R_W] = bd.wheel_radius_m
    arr[P.I_W] = bd.wheel_spin_inertia_kgm2
    arr[P.K_PHI_F] = rl.roll_stiffness_front_nm_per_rad
    arr[P.K_PHI_R] = rl.roll_stiffness_rear_nm_per_rad
    arr[P.C_PHI_F] = rl.roll_damping_front_nms_per_rad
    arr[P.C_PHI_R] = rl.roll_damping_rear_nms_per_rad
    arr[P.EPS_F] = rl.roll_steer_front
    arr[P.EPS_R] = rl.roll_steer_rear
    arr[P.MU] = tr.friction_coefficient if tr is not None else 1.0
    arr[P.F_RR] = tr.rolling_resistance if tr is not None else 0.0
    arr[P.SIGMA_F] = tr.relaxation_length_front_m if tr is not None else 0.0
    arr[P.SIGMA_R] = tr.relaxation_length_rear_m if tr is not None else 0.0
    arr[P.TAU_LT] = LOAD_TRANSFER_TIME_S
    arr[P.TAU_B] = BRAKE_HOLD_TIME_S
    arr[P.G] = GRAVITY_MPS2
    m, g, a, b = c.mass_kg, GRAVITY_MPS2, c.cg_to_front_axle_m, c.cg_to_rear_axle_m
    fz_max = SPIN_LOAD_FACTOR * m * g * max(a, b) / (2.0 * (a + b))
    c_s = max(_longitudinal_stiffness(module, coeffs_f, fz_max, arr[P.MU]),
              _longitudinal_stiffness(module, coeffs_r, fz_max, arr[P.MU]))
    arr[P.K_SPIN] = bd.wheel_radius_m ** 2 * c_s / bd.wheel_spin_inertia_kgm2
    if not math.isfinite(arr[P.K_SPIN]):
        raise ParameterError("body.wheel_spin_inertia_kgm2",
                             f"{bd.wheel_spin_inertia_kgm2!r} kg m^2 is too small to integrate "
                             f"(R^2 C_s / I_w overflows)", vehicle.source or vehicle.name)
    if v_min_mps is None:
        v_min_mps = V_MIN_DEFAULT_MPS
    if not (math.isfinite(v_min_mps) and v_min_mps > 0.0):
        raise ParameterError("v_min_mps", f"must be finite and > 0, got {v_min_mps!r}")
    arr[P.V_MIN] = v_min_mps
    ae = vehicle.aero
    if ae is not None:
        arr[P.DRAG] = ae.drag_coefficient_kg_per_m
        lift_f, lift_r = ae.lift_coefficients_kg_per_m()
        arr[P.LIFT_F] = 0.5 * lift_f  # per wheel: half the axle's
        arr[P.LIFT_R] = 0.5 * lift_r
    dl = vehicle.driveline
    if dl is not None:
        for axle, visc, bias in (("front", P.VISC_F, P.BIAS_F), ("rear", P.VISC_R, P.BIAS_R)):
            kind = getattr(dl, f"differential_{axle}")
            if kind == "locked":
                arr[visc] = bd.wheel_spin_inertia_kgm2 / (2.0 * LOCK_TIME_S)
            elif kind == "limited_slip":
                arr[visc] = getattr(dl, f"viscous_coupling_{axle}_nms_per_rad")
                tbr = getattr(dl, f"torque_bias_ratio_{axle}")
                arr[bias] = (tbr - 1.0) / (tbr + 1.0)
    ratio = vehicle.steering.ratio if vehicle.steering is not None else 1.0
    if free_steering:
        _steering_parameters(arr, vehicle, module, coeffs_f)
    return Params(arr, coeffs_f, coeffs_r, tire_name, module, float(ratio))


def _steering_parameters(arr: np.ndarray, vehicle: Vehicle, module: ModuleType,
                         coeffs_f: np.ndarray) -> None:
    """Fill the free steering system's slots of ``arr`` from ``vehicle.steering`` (see the
    module docstring), with its fastest rate ``RATE_S`` for the sub-steps.

    Raises
    ------
    ParameterError
        No ``steering`` data, or its inertia is 0 (the system would have no dynamics of its
        own: use the first-order 2dof-free model for that limit).
    """
    P = PARAM
    where = vehicle.source or vehicle.name
    vehicle.require("steering", user="8dof-free model (free steering system)")
    st = vehicle.steering
    assert st is not None
    if not st.inertia_kgm2 > 0.0:
        raise ParameterError("steering.inertia_kgm2", f"must be > 0 for the 8dof-free model "
                             f"(the steering system's inertia), got {st.inertia_kgm2!r}", where)
    arr[P.STEER_FREE] = 1.0
    arr[P.J_S] = st.inertia_kgm2
    arr[P.NU_S] = st.damping_nms_per_rad
    arr[P.E_S] = st.trail_m
    arr[P.TC_S] = st.coulomb_friction_nm
    arr[P.N_S] = st.ratio
    c = vehicle.chassis
    fz = arr[P.M] * arr[P.G] * c.cg_to_rear_axle_m / (2.0 * c.wheelbase_m)  # static, per tire
    h = 1.0e-5
    fp = module.forces(fz, h, 0.0, 20.0, arr[P.MU], coeffs_f)
    fm = module.forces(fz, -h, 0.0, 20.0, arr[P.MU], coeffs_f)
    dfy = (fp[1] - fm[1]) / (2.0 * h)
    dmz = (fp[2] - fm[2]) / (2.0 * h)
    stiffness = max(2.0 * (dmz - st.trail_m * dfy), 0.0)  # returning torque per rad, N m
    rates = [st.damping_nms_per_rad / st.inertia_kgm2, math.sqrt(stiffness / st.inertia_kgm2)]
    if st.coulomb_friction_nm > 0.0:
        rates.append(1.0 / arr[P.TAU_B])  # the stuck band's decay
    arr[P.RATE_S] = max(rates)


def _longitudinal_stiffness(module: ModuleType, coeffs: np.ndarray, fz: float,
                            mu: float) -> float:
    """Small-slip ``dFx/dkappa`` of one tire in N (central difference at 20 m/s)."""
    h = 1.0e-5
    fp = module.forces(fz, 0.0, h, 20.0, mu, coeffs)[0]
    fm = module.forces(fz, 0.0, -h, 20.0, mu, coeffs)[0]
    return abs(fp - fm) / (2.0 * h)


def rate_bound(integrator: str) -> float:
    """Largest |lambda h| a sub-step h of ``integrator`` may take (:data:`RK4_RATE_BOUND`;
    :data:`EULER_RATE_BOUND` for ``euler`` and ``semi_implicit_euler``, whose slip and spin
    states take an explicit step; ``solve_ivp`` is held to RK4's)."""
    return (EULER_RATE_BOUND if integrator in ("euler", "semi_implicit_euler")
            else RK4_RATE_BOUND)


def substeps(slip_rate_per_s: float, dt_s: float, integrator: str = "rk4") -> int:
    """Number of equal sub-steps the compiled loops split a step of ``dt_s`` s into when the
    fastest slip mode has the rate ``slip_rate_per_s`` (1/s): the smallest n with
    ``rate dt / n <= bound`` (:func:`rate_bound`), at most :data:`MAX_SUBSTEPS`. The kernels
    compute the same number (``test_eightdof_slip`` checks it)."""
    ratio = slip_rate_per_s * dt_s / rate_bound(integrator)
    if ratio <= 1.0:
        return 1
    if not ratio < MAX_SUBSTEPS:
        return MAX_SUBSTEPS
    return int(math.ceil(ratio))


def check_step(p: Params, dt_s: float, integrator: str = "rk4",
               source: str | None = None) -> int:
    """Check that a step of ``dt_s`` s can integrate the wheels of ``p`` and return the number
    of sub-steps it takes at standstill (the worst case: the spin rate is largest at the slip
    floor, ``K_SPIN / v_min``).

    Raises
    ------
    ParameterError
        If that number exceeds :data:`MAX_SUBSTEPS` (or is not finite): the message names the
        step and the wheel spin inertia and gives the largest step and the smallest inertia
        that would do.
    """
    q = p.arr
    bound = rate_bound(integrator)
    steering = q[PARAM.RATE_S] * dt_s / bound
    if not steering <= MAX_SUBSTEPS:
        raise ParameterError(
            "steering.inertia_kgm2",
            f"{q[PARAM.J_S]:.3g} kg m^2 is too light for the integration step dt_s = "
            f"{dt_s:g} s: the steering system's rate {q[PARAM.RATE_S]:.3g} 1/s would need "
            f"{steering:.3g} {integrator} sub-steps per step (at most {MAX_SUBSTEPS})", source)
    ratio = max(q[PARAM.K_SPIN] / q[PARAM.V_MIN] * dt_s / bound, steering)
    if ratio <= MAX_SUBSTEPS:  # False for NaN
        return max(1, int(math.ceil(ratio)))
    iw = q[PARAM.I_W]
    dt_ok = MAX_SUBSTEPS * bound * q[PARAM.V_MIN] / q[PARAM.K_SPIN]
    iw_ok = iw * ratio / MAX_SUBSTEPS
    raise ParameterError(
        "body.wheel_spin_inertia_kgm2",
        f"{iw:.3g} kg m^2 is too light for the integration step dt_s = {dt_s:g} s: its "
        f"wheel-spin equation would need {ratio:.3g} {integrator} sub-steps per step at "
        f"standstill (at most {MAX_SUBSTEPS}); use dt_s <= {dt_ok:.3g} s or a wheel spin "
        f"inertia >= {iw_ok:.3g} kg m^2", source)


def initial_state(p: Params, speed_mps: float = 0.0) -> np.ndarray:
    """State of straight running at ``speed_mps`` (m/s): wheels spinning at U/R, all else 0."""
    x = np.zeros(N_STATE)
    x[STATE.U] = speed_mps
    x[STATE.OMEGA_FL:STATE.OMEGA_RR + 1] = speed_mps / p.arr[PARAM.R_W]
    return x


# ---------------------------------------------------------------------------------------------
# Readable NumPy reference
# ---------------------------------------------------------------------------------------------

def _solve_body(m: float, ms_h_c: float, iz: float, ixz: float, ix: float,
                fy: float, n: float, roll_moment: float) -> tuple[float, float, float]:
    """Solve ``[[m, 0, -msh c], [0, Iz, -Ixz], [-msh c, -Ixz, Ix]] [V', r', p'] = rhs``
    (``rhs = [fy, n, roll_moment]``)."""
    # p' by eliminating V' and r' (Schur complement on the roll row)
    det = ix - ms_h_c * ms_h_c / m - ixz * ixz / iz
    pd = (roll_moment + ms_h_c * fy / m + ixz * n / iz) / det
    vd = (fy + ms_h_c * pd) / m
    rd = (n + ixz * pd) / iz
    return vd, rd, pd


def _steering_rates(rate: float, torque_nm: float, fy_front: np.ndarray, mz_front: np.ndarray,
                    q: np.ndarray) -> tuple[float, float]:
    """``(d delta_s/dt, d^2 delta_s/dt^2)`` of the free steering system (module docstring):
    driver torque through the ratio, the front tires' aligning moments and lateral forces on
    the caster trail, viscous damping, and the stick-slip Coulomb friction of the wheels'
    form."""
    P = PARAM
    j, cap = q[P.J_S], q[P.TC_S]
    t_other = (q[P.N_S] * torque_nm + float(np.sum(mz_front - q[P.E_S] * fy_front))
               - q[P.NU_S] * rate)
    if j * abs(rate) >= cap * q[P.TAU_B]:  # sliding: Coulomb friction opposes the rate
        if rate > 0.0:
            t_other -= cap
        elif rate < 0.0:
            t_other += cap
        return rate, t_other / j
    if abs(t_other) > cap:  # stuck band, breaking loose
        return rate, (t_other - math.copysign(cap, t_other)) / j
    if abs(rate) > HELD_SPIN_FLOOR_RADPS:  # held: the rate decays to zero
        return rate, -rate / q[P.TAU_B] * (1.0 - abs(t_other) / cap)
    return rate, 0.0


def evaluate(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> tuple[np.ndarray, Aux]:
    """State derivative and per-wheel quantities (NumPy reference and test oracle of the
    compiled kernels; see the module docstring).

    Parameters
    ----------
    t : float
        Time in s (the model is time invariant).
    x : numpy.ndarray
        State, :class:`STATE` order.
    u : numpy.ndarray
        Input, :class:`INPUT` order.
    p : Params
        From :func:`params_for`.

    Returns
    -------
    dx : numpy.ndarray
        dx/dt in :class:`STATE` order (SI).
    aux : Aux
        Loads, slips and tire forces of this evaluation.
    """
    S, I, P = STATE, INPUT, PARAM
    q = p.arr
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    U, V, r, phi, pr, psi = x[S.U], x[S.V], x[S.R], x[S.PHI], x[S.P], x[S.PSI]
    omega = x[S.OMEGA_FL:S.OMEGA_RR + 1]
    m, ms, g = q[P.M], q[P.MS], q[P.G]
    a, b, L = q[P.A], q[P.B], q[P.A] + q[P.B]
    tf, tr = q[P.TF], q[P.TR]
    rw, iw = q[P.R_W], q[P.I_W]
    h = q[P.H_ROLL]
    mu_ = m - ms
    vmin = q[P.V_MIN]

    # road-wheel angles with roll steer (8.32, 8.33)
    free = q[P.STEER_FREE] > 0.0  # the steering system's angle replaces the command
    delta_f = (x[S.DELTA_S] if free else u[I.DELTA_F]) + q[P.EPS_F] * phi
    delta_r = u[I.DELTA_R] + q[P.EPS_R] * phi
    delta = np.array([delta_f, delta_f, delta_r, delta_r])

    # aerodynamic drag (N, along -x at the CG height) and lift per wheel (N)
    drag = q[P.DRAG] * U * abs(U)
    lift = np.array([q[P.LIFT_F], q[P.LIFT_F], q[P.LIFT_R], q[P.LIFT_R]]) * (U * U)

    # normal loads: static less lift, + longitudinal + lateral transfer (Figures 8.3, 8.4);
    # the forces at the ground sum to m ax + drag
    ax_lt, ay_lt = x[S.AX_LT], x[S.AY_LT]
    static = m * g / (2.0 * L) * np.array([b, b, a, a]) - lift
    d_long = (m * ax_lt + drag) * q[P.H_CG] / L
    m_front, m_rear = m * b / L, m * a / L
    d_lat_f = (q[P.K_PHI_F] * phi + q[P.C_PHI_F] * pr
               + m_front * (ms / m) * q[P.H_RC_F] * ay_lt
               + m_front * (mu_ / m) * q[P.H_U] * ay_lt) / tf
    d_lat_r = (q[P.K_PHI_R] * phi + q[P.C_PHI_R] * pr
               + m_rear * (ms / m) * q[P.H_RC_R] * ay_lt
               + m_rear * (mu_ / m) * q[P.H_U] * ay_lt) / tr
    fz = static + np.array([-0.5 * d_long, -0.5 * d_long, 0.5 * d_long, 0.5 * d_long]) \
        + np.array([-d_lat_f, d_lat_f, -d_lat_r, d_lat_r])
    fz = np.maximum(fz, 0.0)

    # wheel-centre velocities (8.34-8.38), wheel frame, slips (8.39-8.46)
    xw = np.array([a, a, -b, -b])
    yw = np.array([0.5 * tf, -0.5 * tf, 0.5 * tr, -0.5 * tr])
    vx_b = U - r * yw
    vy_b = V + r * xw
    cd, sd = np.cos(delta), np.sin(delta)
    vx = vx_b * cd + vy_b * sd
    vy = -vx_b * sd + vy_b * cd
    den = np.maximum(np.abs(vx), vmin)
    alpha = np.arctan2(vy, den)
    kappa = (omega * rw - vx) / den
    sigma = np.array([q[P.SIGMA_F], q[P.SIGMA_F], q[P.SIGMA_R], q[P.SIGMA_R]])
    lagged = sigma > 0.0
    alpha_lag = x[S.ALPHA_FL:S.ALPHA_RR + 1]
    alpha_tire = np.where(lagged, alpha_lag, alpha)
    with np.errstate(divide="ignore"):  # 1/sigma only where sigma > 0
        lag_rate = np.where(lagged, den / sigma, 0.0)  # 1/s
    slip_rate = float(np.max(np.maximum(q[P.K_SPIN] / den, lag_rate)))
    if free:
        slip_rate = max(slip_rate, float(q[P.RATE_S]))

    fx = np.zeros(4)
    fy = np.zeros(4)
    mz = np.zeros(4)
    for i in range(4):
        coeffs = p.coeffs_front if i < 2 else p.coeffs_rear
        fx[i], fy[i], mz[i] = p.tire.forces(float(fz[i]), float(alpha_tire[i]),
                                            float(kappa[i]), float(abs(vx[i])),
                                            float(q[P.MU]), coeffs)

    # body-frame forces and moments (8.9-8.13)
    fxb = fx * cd - fy * sd
    fyb = fx * sd + fy * cd
    sum_fx = fxb.sum()
    sum_fy = fyb.sum()
    sum_n = np.sum(xw * fyb - yw * fxb) + mz.sum()

    c, s = math.cos(phi), math.sin(phi)
    msh = ms * h
    k_phi = q[P.K_PHI_F] + q[P.K_PHI_R]
    c_phi = q[P.C_PHI_F] + q[P.C_PHI_R]
    rhs_y = sum_fy - m * U * r - msh * s * (pr * pr + r * r)
    rhs_l = msh * c * U * r + msh * g * s - k_phi * phi - c_phi * pr
    vd, rd, pd = _solve_body(m, msh * c, q[P.IZ], q[P.IXZ], q[P.IX], rhs_y, sum_n, rhs_l)
    ud = (sum_fx - drag + m * V * r - msh * (s * rd + 2.0 * r * pr * c)) / m

    # the differentials' locking torques (faster wheel to slower), then wheel spin (8.5-8.8)
    # with stick-slip brake and rolling-resistance friction
    drive = u[I.DRIVE_FL:I.DRIVE_RR + 1].astype(float)
    for left, visc, bias in ((0, q[P.VISC_F], q[P.BIAS_F]), (2, q[P.VISC_R], q[P.BIAS_R])):
        dw = omega[left] - omega[left + 1]
        t_axle = abs(drive[left] + drive[left + 1])
        lock = visc * dw + 0.5 * bias * t_axle * min(max(dw / BIAS_BAND_RADPS, -1.0), 1.0)
        slip_rate = max(slip_rate, (2.0 * visc + bias * t_axle / BIAS_BAND_RADPS) / iw)
        drive[left] -= lock
        drive[left + 1] += lock
    cap = np.maximum(u[I.BRAKE_FL:I.BRAKE_RR + 1], 0.0) + q[P.F_RR] * fz * rw
    t_other = drive - rw * fx
    sliding = iw * np.abs(omega) >= cap * q[P.TAU_B]
    held = ~sliding & (np.abs(t_other) <= cap)
    with np.errstate(divide="ignore", invalid="ignore"):  # cap > 0 wherever 'held'
        reserve = 1.0 - np.abs(t_other) / cap
    held_decay = np.where(np.abs(omega) > HELD_SPIN_FLOOR_RADPS,
                          -omega / q[P.TAU_B] * reserve, 0.0)
    friction_sign = np.where(sliding, np.sign(omega), np.sign(t_other))
    omegad = np.where(held, held_decay, (t_other - friction_sign * cap) / iw)

    ax = ud - V * r
    ay = vd + U * r
    dx = np.zeros(N_STATE)
    dx[S.U] = ud
    dx[S.V] = vd
    dx[S.R] = rd
    dx[S.PHI] = pr
    dx[S.P] = pd
    dx[S.OMEGA_FL:S.OMEGA_RR + 1] = omegad
    dx[S.X] = U * math.cos(psi) - V * math.sin(psi)
    dx[S.Y] = U * math.sin(psi) + V * math.cos(psi)
    dx[S.PSI] = r
    dx[S.AX_LT] = (ax - ax_lt) / q[P.TAU_LT]
    dx[S.AY_LT] = (ay - ay_lt) / q[P.TAU_LT]
    dx[S.ALPHA_FL:S.ALPHA_RR + 1] = lag_rate * (alpha - alpha_lag)
    if free:
        dx[S.DELTA_S], dx[S.DELTA_S_RATE] = _steering_rates(
            x[S.DELTA_S_RATE], u[I.STEER_TORQUE], fy[:2], mz[:2], q)
    aux = Aux(fz, alpha_tire.copy(), kappa, fx, fy, mz, float(delta_f), float(delta_r),
              float(ax), float(ay), float(slip_rate), drive)
    return dx, aux


def derivatives(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """State derivative dx/dt of the 8-DOF model (NumPy reference, :class:`STATE` order, SI).

    See :func:`evaluate` for the parameters and the module docstring for the equations.
    """
    return evaluate(t, x, u, p)[0]


def derivatives_compiled(t: float, x: np.ndarray, u: np.ndarray, p: Params) -> np.ndarray:
    """dx/dt of the compiled kernels the simulator integrates (:attr:`Kernels.rhs` of the
    parameters' tire), the signature of :func:`derivatives`; equal to it to round-off
    (``test_eightdof_regression``) and about a hundred times faster: the linearizations
    (:func:`fourws_analysis.linearize.jacobians`) differentiate it."""
    dx = np.zeros(N_STATE)
    kernels_for(p.tire_name).rhs(np.ascontiguousarray(x, dtype=np.float64),
                                 np.ascontiguousarray(u, dtype=np.float64), p.arr,
                                 p.coeffs_front, p.coeffs_rear, dx, np.zeros(N_AUX))
    return dx


# ---------------------------------------------------------------------------------------------
# Compiled kernels
# ---------------------------------------------------------------------------------------------

class Kernels(NamedTuple):
    """Numba-compiled functions of the 8-DOF model for one tire model
    (:mod:`fourws_sim.models.eightdof_kernels`).

    Attributes
    ----------
    rhs : callable
        ``rhs(x, u, q, cf, cr, dx, aux)``: writes dx/dt into ``dx`` and the per-wheel
        quantities (slots ``_AUX_*``) into ``aux``.
    rk4 : callable
        ``rk4(x, u, q, cf, cr, dt, n) -> k``: advances ``x`` in place by ``n`` RK4 steps of
        ``dt`` s, each in as many sub-steps as its state needs (:func:`substeps`); returns
        ``n`` or, if a state became non-finite, the index of that step (``x`` then holds the
        state at its start).
    euler : callable
        Same contract with explicit Euler.
    semi_implicit_euler : callable
        Same contract with semi-implicit Euler (the rates explicitly, then the pose with the
        new rates).
    """

    rhs: Callable[..., Any]
    rk4: Callable[..., Any]
    euler: Callable[..., Any]
    semi_implicit_euler: Callable[..., Any]


_KERNEL_CACHE: dict[str, Kernels] = {}
#: The kernels' template (:mod:`fourws_sim.variants`: compiled once per tire model; it imports
#: this module's slots, never the reverse).
KERNELS_TEMPLATE = f"{__package__}.eightdof_kernels"


def kernel_module(tire_name: str) -> ModuleType:
    """The variant module of :mod:`fourws_sim.models.eightdof_kernels` for tire model
    ``tire_name`` (:func:`fourws_sim.variants.load`: built once per process, compiled at first
    call and cached on disk by numba).

    Raises
    ------
    UnknownNameError
        If ``tire_name`` is not a known tire model.
    """
    return variants.load(KERNELS_TEMPLATE, tire_name)


def kernels_for(tire_name: str) -> Kernels:
    """Compiled kernels for the tire model ``tire_name`` (:func:`kernel_module`), each
    variant calling its tire directly (inlined by LLVM).

    Raises
    ------
    UnknownNameError
        If ``tire_name`` is not a known tire model.
    """
    if tire_name not in _KERNEL_CACHE:
        module = kernel_module(tire_name)
        _KERNEL_CACHE[tire_name] = Kernels(module.rhs, module.rk4, module.euler,
                                           module.semi_implicit_euler)
    return _KERNEL_CACHE[tire_name]


def lane_kernels_for(tire_name: str) -> Any:
    """The kernel module of tire model ``tire_name`` if it has the batch kernels of many
    points at once (``rhs_lanes``, ``rk4_lanes``, ``pack_lane``; a tire with ``forces_lane``,
    :mod:`fourws_sim.lanes`), else None.

    Raises
    ------
    UnknownNameError
        If ``tire_name`` is not a known tire model.
    """
    module = kernel_module(tire_name)
    return module if module.HAS_LANES else None


def aux_from_array(aux: np.ndarray) -> Aux:
    """Unpack the compiled kernels' auxiliary array into an :class:`Aux`."""
    return Aux(aux[_AUX_FZ:_AUX_FZ + 4].copy(), aux[_AUX_ALPHA:_AUX_ALPHA + 4].copy(),
               aux[_AUX_KAPPA:_AUX_KAPPA + 4].copy(), aux[_AUX_FX:_AUX_FX + 4].copy(),
               aux[_AUX_FY:_AUX_FY + 4].copy(), aux[_AUX_MZ:_AUX_MZ + 4].copy(),
               float(aux[_AUX_DELTA_F]), float(aux[_AUX_DELTA_R]), float(aux[_AUX_AX]),
               float(aux[_AUX_AY]), float(aux[_AUX_RATE]),
               aux[_AUX_DRIVE:_AUX_DRIVE + 4].copy())
