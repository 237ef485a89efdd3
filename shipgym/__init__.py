"""shipgym: a MuJoCo simulator of ships in the horizontal plane (surge, sway, yaw; roll).

Importing ``shipgym`` registers the Gymnasium ids ``shipgym/Harbour-v0``,
``shipgym/StationKeeping-v0`` and ``shipgym/Tracking-v0`` (for any vessel, ``vessel=``) and
the Blue Lady's aliases ``shipgym/BlueLadyHarbour-v0``, ``shipgym/BlueLadyStationKeeping-v0``,
``shipgym/BlueLadyTracking-v0``. :func:`vessels` lists the packaged vessels,
:func:`load_vessel` loads one by name or a package folder. Subpackages: ``dynamics`` (pure
NumPy models, actuators, vessels), ``disturbances`` (wind, waves, current), ``guidance``,
``observers``, ``controllers``, ``envs`` (MuJoCo physics and tasks), ``metrics``. See the
README for the quick start.
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
