"""Kinematics of the RV reducer (two-stage: involute planetary + cycloid-pin).

Arrangement (as in :cite:`seed000,seed001,seed002,seed003,seed004`): the input shaft carries the sun (z_s); each of
the n planets (z_p) is fixed to a crankshaft borne in the carrier; the cranks'
eccentrics (eccentricity a) drive the cycloid discs (z_c teeth) inside the fixed
pin housing (z_rp pins); the carrier is the output. Angular speeds are signed
(same positive sense for all members), SI [rad/s]; frequencies in Hz.

Derivation (Willis' equation for each stage, e.g. :cite:`muller1982`;
:cite:`blagojevic2011` for the RV drive):

* first stage, relative to the carrier H:
  w_crank - w_H = -(z_s / z_p)(w_in - w_H);
* second stage, relative to the eccentric (crank) whose absolute orbit speed is
  w_e = w_crank: w_disc - w_e = (z_rp / z_c)(0 - w_e); the discs only translate
  relative to the carrier (they sit on all cranks), so w_disc = w_H;
* hence w_H = w_in / i with i = 1 + z_p z_rp / (z_s (z_rp - z_c)).

Pure vectorised functions, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexrv.errors import InputError
from flexrv.units import TWO_PI


def total_ratio(z_s, z_p, z_c, z_rp):
    """Total ratio i = w_in / w_out = 1 + z_p z_rp / (z_s (z_rp - z_c)) (:cite:`seed000,seed001`).

    Parameters
    ----------
    z_s, z_p : teeth of sun and planet [-]; z_c, z_rp : disc teeth and pins [-].
    """
    z_s, z_p, z_c, z_rp = (np.asarray(v) for v in (z_s, z_p, z_c, z_rp))
    if np.any(z_rp - z_c <= 0):
        raise InputError(f"pin count z_rp = {z_rp} must exceed the disc teeth z_c = {z_c}")
    return 1.0 + z_p * z_rp / (z_s * (z_rp - z_c))


@dataclass(frozen=True)
class MemberSpeeds:
    """Signed angular speeds [rad/s] of every member (absolute = housing frame).

    Attributes
    ----------
    ratio : total ratio i [-].
    input : input shaft = sun.
    sun_relative : sun relative to the carrier, w_in - w_H.
    carrier : carrier = output.
    crank_absolute : planet = crankshaft, absolute (:cite:`seed002`'s "585 r/min").
    crank_relative : planet = crankshaft relative to the carrier (:cite:`seed002`'s 10 Hz).
    disc_rotation : cycloid disc spin, absolute (= carrier).
    disc_orbit : angular speed of the disc centre about the reducer axis
        (= crank_absolute: all eccentrics are parallel).
    disc_orbit_relative : disc-centre orbit relative to the carrier (= crank_relative).
    """

    ratio: float
    input: np.ndarray
    sun_relative: np.ndarray
    carrier: np.ndarray
    crank_absolute: np.ndarray
    crank_relative: np.ndarray
    disc_rotation: np.ndarray
    disc_orbit: np.ndarray
    disc_orbit_relative: np.ndarray


def member_speeds(input_speed, z_s: int, z_p: int, z_c: int, z_rp: int) -> MemberSpeeds:
    """Absolute and carrier-relative speeds of all members for an input speed
    [rad/s] (fixed pin housing, input on the sun, output on the carrier); formulas
    in the module docstring."""
    w_in = np.asarray(input_speed, dtype=float)
    if not np.all(np.isfinite(w_in)):
        raise InputError(f"input_speed must be finite, got {input_speed!r}")
    i = float(total_ratio(z_s, z_p, z_c, z_rp))
    w_h = w_in / i
    w_rel = -(z_s / z_p) * (w_in - w_h)
    w_crank = w_h + w_rel
    return MemberSpeeds(
        ratio=i,
        input=w_in,
        sun_relative=w_in - w_h,
        carrier=w_h,
        crank_absolute=w_crank,
        crank_relative=w_rel,
        disc_rotation=w_h,
        disc_orbit=w_crank,
        disc_orbit_relative=w_rel,
    )


@dataclass(frozen=True)
class CharacteristicFrequencies:
    """Characteristic frequencies [Hz] (all >= 0), each named by what it is.

    With the pins fixed in the housing and the discs turning with the carrier (RV arrangement),
    w_rel = crank speed relative to the carrier, w_H = carrier speed, w_e = w_H + w_rel = absolute
    crank (eccentric, disc-centre orbit) speed, and z_c (w_H - w_e) = -z_rp w_e (Willis, module
    docstring):

    input : input shaft rotation |w_in|/2pi (:cite:`seed002` Table 4: 20.25 Hz).
    crank_rotation : crank rotation relative to the carrier |w_rel|/2pi (Table 4: 10 Hz).
    carrier : carrier (output) rotation = crank revolution |w_H|/2pi (Table 4: 0.25 Hz).
    crank_absolute : crank rotation in the housing frame |w_e|/2pi.
    first_stage_mesh : involute sun-planet mesh, z_s |w_in - w_H| / 2pi (= z_p |w_rel| / 2pi;
        Table 4: 320 Hz).
    cycloid_mesh : cycloid-pin mesh, z_c |w_rel| / 2pi = z_rp |w_e| / 2pi: the rate at which the
        load passes from one pin to the next (the loaded zone turns with the eccentric at w_e past
        z_rp pins; equally, the disc teeth pass the eccentric's direction at w_rel). This is the
        second-stage line of the TE spectrum (tests/test_kinematics.py runs a rigid model and
        finds it there; Table 4: 390 Hz).
    disc_tooth_pin_passing : pins passed by one disc tooth, z_rp |w_H| / 2pi = (z_rp - z_c)
        |w_rel| / 2pi (the disc turns past the fixed pins with the carrier; 10 Hz for RV-40E).
    pins_x_crank_rotation : z_rp |w_rel| / 2pi, the pin count times the crank rotation relative
        to the carrier: :cite:`seed002` Table 4's "cycloidal gear" and "pin gear" 400 Hz. It is not a
        mesh frequency of the RV arrangement (that is ``cycloid_mesh``, 10 Hz lower for RV-40E)
        and no TE line is expected there; kept to reproduce the seed's table. (Named
        ``pin_passing`` before; its docstring "pins passed by one disc tooth" described
        ``disc_tooth_pin_passing``.)
    """

    input: np.ndarray
    crank_rotation: np.ndarray
    carrier: np.ndarray
    crank_absolute: np.ndarray
    first_stage_mesh: np.ndarray
    cycloid_mesh: np.ndarray
    disc_tooth_pin_passing: np.ndarray
    pins_x_crank_rotation: np.ndarray


#: field names of :class:`CharacteristicFrequencies`, in order
FREQUENCY_NAMES = (
    "input",
    "crank_rotation",
    "carrier",
    "crank_absolute",
    "first_stage_mesh",
    "cycloid_mesh",
    "disc_tooth_pin_passing",
    "pins_x_crank_rotation",
)


def characteristic_frequencies(input_speed, z_s: int, z_p: int, z_c: int, z_rp: int) -> CharacteristicFrequencies:
    """Characteristic frequencies [Hz] for an input speed [rad/s] (see
    :class:`CharacteristicFrequencies`). For the RV-40E at 1215 r/min, :cite:`seed002` Table 4 lists
    20.25 (input), 10 (crank rotation), 0.25 (carrier), 320 (first-stage mesh), 390
    (cycloid mesh) and 400 Hz (``pins_x_crank_rotation``)."""
    s = member_speeds(input_speed, z_s, z_p, z_c, z_rp)
    f = 1.0 / TWO_PI
    rel = np.abs(s.crank_relative) * f
    return CharacteristicFrequencies(
        input=np.abs(s.input) * f,
        crank_rotation=rel,
        carrier=np.abs(s.carrier) * f,
        crank_absolute=np.abs(s.crank_absolute) * f,
        first_stage_mesh=z_s * np.abs(s.sun_relative) * f,
        cycloid_mesh=z_c * rel,
        disc_tooth_pin_passing=z_rp * np.abs(s.carrier) * f,
        pins_x_crank_rotation=z_rp * rel,
    )


def harmonics(frequency, count: int = 4):
    """First ``count`` harmonics k f (k = 1..count) [Hz], shape (..., count)."""
    if count < 1:
        raise InputError(f"count = {count} must be >= 1")
    return np.asarray(frequency, dtype=float)[..., None] * np.arange(1, count + 1)


@dataclass(frozen=True)
class ReducerKinematics:
    """Kinematics of a design at one input speed (SI speeds, Hz frequencies)."""

    input_speed: float
    speeds: MemberSpeeds
    frequencies: CharacteristicFrequencies


def reducer_kinematics(reducer, input_speed: float | None = None) -> ReducerKinematics:
    """Kinematics of a :class:`flexrv.design.model.Reducer` at ``input_speed``
    [rad/s] (default: the operating point's input speed)."""
    fs, ss = reducer.first_stage, reducer.second_stage
    w = reducer.operating.input_speed if input_speed is None else float(input_speed)
    args = (fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)
    return ReducerKinematics(
        input_speed=w, speeds=member_speeds(w, *args), frequencies=characteristic_frequencies(w, *args)
    )
