"""shipgym: a MuJoCo simulator of ships in the horizontal plane (surge, sway, yaw).

Subpackages: ``dynamics`` (pure NumPy model), ``disturbances`` (wind), ``envs`` (MuJoCo
physics). See the README for the quick start.
"""

__version__ = "0.1.0"
