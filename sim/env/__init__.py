"""The Gymnasium env of the QCar 2 on the indoor map."""

import lazy_loader

# Each name is imported on first use (SPEC 1): a command's --help never waits for the simulator.
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "config": ["EnvConfig"],
    "qcar2_env": ["QCar2Env"],
})
