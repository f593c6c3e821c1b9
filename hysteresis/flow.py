"""Branch flows: what an integrator needs while the input of a continuous operator moves one way.

A continuous hysteresis operator (play, generalized play, Prandtl–Ishlinskii, continuous
Preisach) is, for a fixed direction of input motion, a smooth function of the input between
*breakpoints*. :meth:`ContinuousHysteron.branch_flow(state, direction)
<hysteresis.base.ContinuousHysteron.branch_flow>` describes that piece as a
:class:`BranchFlow`: the operator's memory variables, the output as a function of the input with
its partial derivatives, the next breakpoint and what happens to the memory there. The generic
continuous engine of the oscillator (:mod:`oscillators.engines.continuous`) integrates any
operator that provides it, tangent flow included.

Memory variables
----------------
``memory`` holds the values ``m_i`` of the operator's memory variables at the branch start
(input ``u0``) and ``labels`` names them. A label is stable and unique for as long as the
variable lives: the play's wagon is ``"w"``, the wagons of a Prandtl–Ishlinskii operator are
``"w0" ... "w{K-1}"`` (in the order of increasing width), the remembered extrema of a continuous
Preisach staircase are ``"M1", "m1", "M2", "m2", ...`` (position in the staircase, which only
grows and shrinks at its end, so a label is reused only after its variable was wiped out).

On the branch each memory variable is either

* **frozen**: ``m_i`` stays constant, ``δm_i`` stays constant (a play wagon strictly inside,
  every remembered Preisach extremum);
* **slaved** (``slaved[i]``): ``m_i`` follows the input, ``m_i(u) = m_i(u0) + (u − u0)``, and so
  does its perturbation, ``δm_i = δu`` (a wagon dragged by the finger on a wall).

A variable that follows some other function of the input and the memory is *driven* and is not
among ``labels`` on that branch (see "Driven memory" below).

Output and derivatives
----------------------
``output(u)`` is ``y(u)`` on the branch (frozen memory fixed, slaved memory following ``u``);
``partials(u)`` returns ``(∂y/∂u, ∂y/∂m)``: the partial derivatives of ``y(u; m)`` with respect
to the input and to each memory variable (array of length ``len(memory)``), *all memory held
fixed* in the first. The slope of the branch is therefore
``dy/du = ∂y/∂u + Σ_{slaved} ∂y/∂m_i`` (:meth:`BranchFlow.slope`), and a perturbation moves the
output by ``δy = ∂y/∂u δu + Σ_i ∂y/∂m_i δm_i``. Both callables are vectorised (an array of
inputs gives arrays, ``partials`` then an ``(..., n)`` array) and cheap on a scalar; with
``constant_partials`` the partials do not depend on ``u`` (play inside, Prandtl–Ishlinskii), so
an integrator may evaluate them once per branch.

Events
------
``breakpoint`` is the input at which the branch ends in its direction (``±inf`` if none):

* a **wall hit** (play, Prandtl–Ishlinskii): the memory variables ``breakpoint_resets`` start
  being dragged; their perturbations are reset, ``δm_i := δu`` (paper ``V_out``);
* a **wipe-out** (continuous Preisach): the input reaches a remembered extremum of the same kind,
  which is removed together with its partner (``breakpoint_removes``); their rows of the tangent
  map are dropped.

The output is continuous at both, so the oscillator's (q, v) perturbations need no correction
there. A composite with piecewise-constant parts (``0.5 * play + 0.5 * relays``,
:mod:`hysteresis.algebra`) has a third kind:

* a **jump** (``breakpoint_jump != 0``): relays switch and the output changes by
  ``breakpoint_jump`` there. The breakpoint is the first input at which the new output holds:
  a rising input switches a relay at ``u = α`` (``u >= α``), a falling one at the largest float
  below ``β`` (``u < β``), so the branch reports ``nextafter(β, -inf)`` and an integrator that
  stops exactly at the breakpoint and applies the operator there sees the switch. The
  oscillator's saltation there is ``δv += C·Δy/v*·δq`` (paper eq. ``salt_matrix``). A jump
  whose input moves with the memory (a cascade's relay threshold reached through a branch
  ``x(u; m)`` of its inner operator) says how in ``breakpoint_gradient``:
  ``∂u*/∂m_i`` for the frozen variables, and the saltation becomes
  ``δv += C·Δy/v*·(δq − Σ_frozen ∂u*/∂m_i δm_i)`` (the event time moves by
  ``(∂u*/∂m·δm − δq)/v*``).

A **reversal** of the input at ``u*`` (``v = 0``) ends the branch too: play and
Prandtl–Ishlinskii push nothing (``V_in = I``); a continuous Preisach model remembers ``u*`` as a
new extremum (``reversal_pushes``), a new memory variable with ``δm := δu``. A branch that starts
with such a reversal relative to its state (the state's last motion went the other way) flags
the variable it created at ``u0`` in ``pushed``. Where the pushed value is not the input itself
(a cascade whose outer Preisach model remembers the *inner output* ``x(u0; m)``),
``pushed_gradient(u0) -> (d_du (n_p,), d_dm (n_p, n))`` gives it,
``δm_p := d_du·δu + d_dm @ δm`` (rows in the order of the pushed variables, columns over all
memory variables, zero on the pushed ones); ``None`` means ``δm_p := δu``. A variable flagged
``pushed`` on two consecutive branches (the remembered value has not moved in between: a
cascade's inner output stayed constant while the input turned and hit a wall) is one variable,
created once: an integrator keeps the perturbation it gave it at the first branch.

Driven memory
-------------
A cascade ``outer[inner[u]]`` has memory variables that follow the *outer's* input
``x = x(u; m)`` rather than ``u``: a wagon of the outer play dragged by ``x`` moves by
``δx = ∂x/∂u δu + ∂x/∂m δm``, which ``slaved`` (``δm = δu``) cannot say. Such variables are
**driven** on the branch: they are listed in ``driven_labels``, *not* in ``labels`` (they are
no coordinates of the branch: output and partials already contain them by the chain rule), and
``driven(u) -> (values (n_d,), d_du (n_d,), d_dm (n_d, n))`` gives their values and gradient,
``δm_driven = d_du·δu + d_dm @ δm`` with ``δm`` the perturbations of ``labels`` (a slaved
variable's is ``δu``; ``driven`` is called with a scalar ``u``). ``slaved`` is the special case
``d_du = 1, d_dm = 0`` of a variable that stays a coordinate. At an event an integrator

* initialises a variable that was driven on the old branch and is a memory variable of the new
  one (the same label in the new ``labels``) from the old gradient at the event,
  ``δm := d_du·δq + d_dm @ δm_old``; it is then no free direction (like a reset);
* drops a memory variable that becomes driven (its label leaves ``labels``), like a removed one.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from hysteresis._validation import readonly_array

__all__ = ["BranchFlow", "CompiledFlow"]


@dataclass(frozen=True)
class BranchFlow:
    """The branch a continuous operator follows while its input moves in ``direction``.

    See the module docstring for the meaning of every field.

    Attributes
    ----------
    direction:
        +1 (rising input) or -1 (falling input).
    input:
        ``u0``, the input at the start of the branch (the state's current input).
    labels:
        Names of the memory variables (stable and unique while alive).
    memory:
        Values ``m_i`` at ``u0`` (read-only).
    slaved:
        ``slaved[i]``: ``m_i`` (and ``δm_i``) follow the input on this branch; else frozen.
    output:
        ``y(u)`` on the branch (vectorised).
    partials:
        ``u -> (∂y/∂u, ∂y/∂m)`` (vectorised; ``∂y/∂m`` has length ``len(memory)``).
    breakpoint:
        Input at which the branch ends in its direction (``±inf`` if it never does).
    breakpoint_resets:
        Labels whose perturbation is reset ``δm := δu`` at the breakpoint (wall hit, ``V_out``).
    breakpoint_removes:
        Labels removed at the breakpoint (wiped-out extrema).
    breakpoint_jump:
        Change of the output when the input reaches the breakpoint (0: the output is
        continuous there; a composite's relays that switch there: their weighted jumps).
    reversal_pushes:
        True if a reversal of the input at the end of this branch creates a new memory variable
        (the reversal input, ``δm := δu``): continuous Preisach. False: ``V_in = I``.
    pushed:
        ``pushed[i]``: memory variable ``i`` was created at ``u0`` by a reversal relative to the
        state (``δm_i := δu`` there).
    constant_partials:
        True if ``partials`` does not depend on ``u``.
    breakpoint_gradient:
        ``∂u*/∂m_i`` of the breakpoint for the frozen memory variables (length ``len(memory)``,
        read-only; slaved entries are ignored), used with ``breakpoint_jump``; ``None``: the
        breakpoint does not move with the memory.
    driven_labels:
        Names of the driven variables (functions of the input and of the memory on this branch,
        not in ``labels``).
    driven:
        ``u -> (values, d_du, d_dm)`` of the driven variables (scalar ``u``); required with
        ``driven_labels``.
    pushed_gradient:
        ``u0 -> (d_du, d_dm)`` of the pushed variables (``None``: ``δm := δu``).
    """

    direction: int
    input: float
    labels: tuple[str, ...]
    memory: np.ndarray
    slaved: np.ndarray
    output: Callable
    partials: Callable
    breakpoint: float
    breakpoint_resets: tuple[str, ...] = ()
    breakpoint_removes: tuple[str, ...] = ()
    breakpoint_jump: float = 0.0
    reversal_pushes: bool = False
    pushed: np.ndarray | None = None
    constant_partials: bool = False
    breakpoint_gradient: np.ndarray | None = None
    driven_labels: tuple[str, ...] = ()
    driven: Callable | None = None
    pushed_gradient: Callable | None = None

    def __post_init__(self) -> None:
        if self.direction not in (-1, 1):
            raise ValueError(f"direction must be +1 or -1, got {self.direction!r}")
        n = len(self.labels)
        if len(set(self.labels)) != n:
            raise ValueError(f"labels must be unique, got {self.labels}")
        object.__setattr__(self, "memory", readonly_array(self.memory))
        object.__setattr__(self, "slaved", readonly_array(self.slaved, bool))
        pushed = np.zeros(n, dtype=bool) if self.pushed is None else self.pushed
        object.__setattr__(self, "pushed", readonly_array(pushed, bool))
        for name in ("memory", "slaved", "pushed"):
            if getattr(self, name).shape != (n,):
                raise ValueError(f"{name} must have one entry per label ({n})")
        bp = float(self.breakpoint)
        if bp == bp and (bp - self.input) * self.direction < 0:
            raise ValueError(
                f"breakpoint {bp} lies behind the input {self.input} in direction {self.direction}"
            )
        jump = float(self.breakpoint_jump)
        if not math.isfinite(jump) or (jump != 0.0 and not math.isfinite(bp)):
            raise ValueError(
                f"breakpoint_jump must be finite and needs a finite breakpoint, got {jump} at "
                f"breakpoint {bp}"
            )
        object.__setattr__(self, "breakpoint_jump", jump)
        for name in ("breakpoint_resets", "breakpoint_removes"):
            unknown = set(getattr(self, name)) - set(self.labels)
            if unknown:
                raise ValueError(f"{name} names unknown memory labels {sorted(unknown)}")
        if self.breakpoint_gradient is not None:
            grad = readonly_array(self.breakpoint_gradient)
            if grad.shape != (n,) or np.any(np.isnan(grad)):
                raise ValueError(
                    f"breakpoint_gradient must have one (non-NaN) entry per label ({n}), got "
                    f"shape {grad.shape}"
                )
            object.__setattr__(self, "breakpoint_gradient", grad)
        driven = tuple(self.driven_labels)
        object.__setattr__(self, "driven_labels", driven)
        if len(set(driven)) != len(driven) or set(driven) & set(self.labels):
            raise ValueError(
                f"driven_labels must be unique and not memory labels, got {driven} with labels "
                f"{self.labels}"
            )
        if bool(driven) != callable(self.driven):
            raise ValueError("driven must be a callable exactly when driven_labels are given")
        if self.pushed_gradient is not None and not callable(self.pushed_gradient):
            raise ValueError("pushed_gradient must be a callable or None")

    @property
    def n_memory(self) -> int:
        """Number of memory variables."""
        return len(self.labels)

    def slope(self, u) -> np.ndarray | float:
        """Total derivative ``dy/du`` along the branch, ``∂y/∂u + Σ_slaved ∂y/∂m_i``."""
        d_u, d_m = self.partials(u)
        d_m = np.asarray(d_m, dtype=np.float64)
        if not np.any(self.slaved):
            return d_u
        return d_u + np.sum(d_m[..., self.slaved], axis=-1)

    def memory_at(self, u) -> np.ndarray:
        """Memory values at input ``u`` on this branch (slaved ones moved by ``u − u0``)."""
        u = np.asarray(u, dtype=np.float64)
        return self.memory + self.slaved * (u[..., None] - self.input)


@dataclass(frozen=True, eq=False)
class CompiledFlow:
    """What the oscillator's compiled continuous engine needs (a fast path, see
    :meth:`hysteresis.base.ContinuousHysteron.compiled_flow`).

    ``kind`` ``"prandtl_ishlinskii"``: ``half_widths`` ``r_i`` and ``weights`` ``a_i`` of the
    plays (the states have ``positions`` and ``input``; the operator rebuilds a state with
    ``state(positions, input)``), optionally ``spreads`` ``R_i`` (``0``: the play's output is
    its wagon ``w_i``; ``R_i > 0``: ``erf(w_i/(√2 R_i))``, an erf play), so that
    ``y = Σ a_i f_i(w_i)``, and relays (``relay_alpha``, ``relay_beta``, ``relay_weights`` of
    any sign: ``y += Σ c_j·y_j``, the relays of a composite ``play + relays``). A composite
    whose states are not of that form hands over ``positions(state)`` (the wagon positions of
    a state), with relays ``relay_outputs(state)`` (their ±1 in the order of the thresholds),
    and ``make_state(positions, input[, relay_outputs])`` (the state from them) instead.
    ``kind`` ``"preisach"``: ``everett``, the model's Everett
    function as a :class:`~hysteresis.preisach.everett_table.CompiledEverett` (the states have
    ``extrema``; the operator rebuilds a state with ``state_from_extrema(extrema)``).
    ``kind`` ``"duhem"``: a Duhem operator whose slope is one of the compiled right-hand sides
    of :mod:`hysteresis._duhem_kernels`: ``model`` names it (``"bouc_wen"``,
    ``"jiles_atherton"``), ``parameters`` maps the model's parameter names to values,
    ``memory(state)`` is the internal variable ``z`` of a state and ``make_state(z, input,
    direction)`` the state from it; the engine integrates ``(q, v, z)`` in time and names the
    tangent row of ``z`` ``label(0)``.
    ``label(i)`` names memory variable ``i`` as :meth:`BranchFlow.labels` does (``"w3"``,
    ``"m2"``, ...), so that both engines name the tangent space alike.
    """

    kind: str
    label: Callable[[int], str]
    half_widths: np.ndarray | None = None
    weights: np.ndarray | None = None
    everett: object | None = None
    spreads: np.ndarray | None = None
    positions: Callable | None = None
    make_state: Callable | None = None
    relay_alpha: np.ndarray | None = None
    relay_beta: np.ndarray | None = None
    relay_weights: np.ndarray | None = None
    relay_outputs: Callable | None = None
    model: str | None = None
    parameters: Mapping[str, float] | None = None
    memory: Callable | None = None

    def __post_init__(self) -> None:
        if self.kind == "prandtl_ishlinskii":
            hw = readonly_array(self.half_widths)
            wt = readonly_array(self.weights)
            if hw.ndim != 1 or hw.shape != wt.shape or (hw.size == 0 and self.relay_alpha is None):
                raise ValueError("half_widths and weights must be 1-D of one (non-zero) length")
            object.__setattr__(self, "half_widths", hw)
            object.__setattr__(self, "weights", wt)
            spreads = np.zeros(hw.size) if self.spreads is None else self.spreads
            sp = readonly_array(spreads)
            if sp.shape != hw.shape or not np.all(sp >= 0.0):
                raise ValueError("spreads must be >= 0, one per play (0: the identity shape)")
            object.__setattr__(self, "spreads", sp)
            if (self.positions is None) != (self.make_state is None):
                raise ValueError("positions and make_state come together (a composite's states)")
            if self.relay_alpha is not None:
                a = readonly_array(self.relay_alpha)
                b = readonly_array(self.relay_beta)
                c = readonly_array(self.relay_weights)
                if not (a.ndim == 1 and a.shape == b.shape == c.shape and np.all(a >= b)):
                    raise ValueError("relay thresholds need alpha >= beta and one weight each")
                if self.relay_outputs is None or self.make_state is None:
                    raise ValueError("relays come with relay_outputs and make_state")
                object.__setattr__(self, "relay_alpha", a)
                object.__setattr__(self, "relay_beta", b)
                object.__setattr__(self, "relay_weights", c)
        elif self.kind == "preisach":
            if self.everett is None:
                raise ValueError("a 'preisach' CompiledFlow needs its compiled Everett function")
        elif self.kind == "duhem":
            if not isinstance(self.model, str) or not self.model:
                raise ValueError(f"a 'duhem' CompiledFlow needs a model name, got {self.model!r}")
            if self.memory is None or self.make_state is None or self.parameters is None:
                raise ValueError("a 'duhem' CompiledFlow needs parameters, memory and make_state")
            values = {str(k): float(v) for k, v in dict(self.parameters).items()}
            if not all(math.isfinite(v) for v in values.values()):
                raise ValueError(f"parameters of a 'duhem' CompiledFlow must be finite: {values}")
            object.__setattr__(self, "parameters", values)
        else:
            raise ValueError(
                f"kind must be 'prandtl_ishlinskii', 'preisach' or 'duhem', got {self.kind!r}"
            )
