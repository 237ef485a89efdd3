"""shipgym: a MuJoCo simulator of ships as Gymnasium environments (surge, sway, yaw; roll).

A vessel is a data package (hull model, actuators, windage; :func:`vessels` lists the packaged
ones, :func:`load_vessel` loads one by name or a package folder): the 1:24 Blue Lady training
model, the offshore vessels Star Hercules and Wimpey Sealab, KVLCC2 tankers, and the 4-DOF
(roll) container ship, naval vessel and Van der Klugt model. Importing ``shipgym`` registers
the Gymnasium ids of :data:`ENV_IDS`: the harbour manoeuvre, station keeping and tracking
(``shipgym/Harbour-v0``, ``StationKeeping-v0``, ``Tracking-v0``, for any vessel with
``vessel=``, and the Blue Lady's aliases ``BlueLadyHarbour-v0``, ...), offshore dynamic
positioning with wave filtering (``DPStationKeeping-v0``, ``DPSwayStep-v0``), rudder-roll
stabilisation (``RudderRollStabilisation-v0``, ``NavalRollDamping-v0``), IMO sea trials and
course keeping through a DGPS receiver's filter (``SeaTrial-v0``, ``CourseKeeping-v0``); each
has a native batched form (``gymnasium.make_vec``). :func:`make` adds a Kalman observer and a
PID or LQ controller; a learned (stable-baselines3) policy wraps that stack. Subpackages:
``dynamics`` (pure NumPy hull models, actuators, vessels), ``disturbances`` (wind, waves,
current), ``guidance``, ``observers``, ``controllers``, ``envs`` (MuJoCo physics, tasks, vector
envs), ``sim`` (the compiled physics step), ``dp`` and ``trials`` (DP and sea-trial
evaluation), ``rrs`` (roll stabilisation benchmark), ``rl`` (training learned controllers),
``viz`` (rerun recordings, figures); ``metrics``, ``scenarios`` and the ``shipgym`` command
line. See the README for the quick start.
"""

from importlib import metadata as _metadata

from shipgym.dynamics.vessel import load_vessel, vessels
from shipgym.envs.registration import ENV_IDS, register_envs

try:  # the installed distribution's version (pyproject.toml), one source of truth
    __version__ = _metadata.version("shipgym")
except _metadata.PackageNotFoundError:  # run from a source tree that was never installed
    __version__ = "0+unknown"

register_envs()

__all__ = ["ENV_IDS", "__version__", "load_vessel", "make", "vessels"]


def make(env_id: str, *, observer=None, controller=None, **kwargs):  # type: ignore[no-untyped-def]
    """``gym.make(env_id, **kwargs)`` with the wrapper stack env -> observer -> controller.

    Args:
        env_id: a registered id (see ``shipgym.ENV_IDS``) or a short name
            (``harbour``, ``station-keeping``, ``tracking``: the Blue Lady's, or with
            ``vessel=`` that vessel's task).
        observer: ``None``/``"truth"`` or an observer name (``dkf``, ``kbf``, ``ekf``, ...).
        controller: ``None`` (raw thruster actions) or a controller name (``pid``,
            ``pid-seed``).
        **kwargs: environment arguments (``vessel=`` a name of :func:`vessels` or a path).
    """
    from shipgym.stacks import make as _make

    return _make(env_id, observer=observer, controller=controller, **kwargs)
