"""usarsim: a USARSim-compatible robot simulator on MuJoCo."""

__version__ = "0.1.0"
