"""shipgym: a MuJoCo simulator of ships in the horizontal plane (surge, sway, yaw).

Importing ``shipgym`` registers the Gymnasium ids ``shipgym/BlueLadyHarbour-v0``,
``shipgym/BlueLadyStationKeeping-v0`` and ``shipgym/BlueLadyTracking-v0``. Subpackages:
``dynamics`` (pure NumPy model), ``disturbances`` (wind), ``guidance``, ``controllers``,
``envs`` (MuJoCo physics and tasks), ``metrics``. See the README for the quick start.
"""

from importlib import metadata as _metadata

from shipgym.envs.registration import ENV_IDS, register_envs

try:  # the installed distribution's version (pyproject.toml), one source of truth
    __version__ = _metadata.version("shipgym")
except _metadata.PackageNotFoundError:  # run from a source tree that was never installed
    __version__ = "0+unknown"

register_envs()

__all__ = ["ENV_IDS", "__version__", "make"]


def make(env_id: str, *, observer=None, controller=None, **kwargs):  # type: ignore[no-untyped-def]
    """``gym.make(env_id, **kwargs)`` with the wrapper stack env -> observer -> controller.

    Args:
        env_id: a registered id (see ``shipgym.ENV_IDS``) or a short name
            (``harbour``, ``station-keeping``, ``tracking``).
        observer: ``None``/``"truth"`` or an observer name (``dkf``, ``kbf``, ``ekf``, ...).
        controller: ``None`` (raw thruster actions) or a controller name (``pid``,
            ``pid-seed``).
        **kwargs: environment arguments.
    """
    from shipgym.envs.make import make as _make

    return _make(env_id, observer=observer, controller=controller, **kwargs)
