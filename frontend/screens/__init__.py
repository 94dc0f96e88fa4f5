"""The screens of the work area, one module each. `SCREENS` is the one list of them: the
workspace makes a tab of each, in this order (frontend/screen_registry.py)."""

from __future__ import annotations

from frontend.screen_registry import Screen
from frontend.screens.code import Code
from frontend.screens.documentation import Documentation
from frontend.screens.events import Events
from frontend.screens.forcing import Forcing
from frontend.screens.io import Io
from frontend.screens.logic import Logic
from frontend.screens.online_test import OnlineTest
from frontend.screens.parameters import Parameters
from frontend.screens.reload import Reload
from frontend.screens.resources import Resources
from frontend.screens.settings import SettingsScreen
from frontend.screens.single_step import SingleStep
from frontend.screens.tests import Tests
from frontend.screens.trends import Trends

SCREENS: tuple[type[Screen], ...] = (
    Resources,
    OnlineTest,
    SingleStep,
    Forcing,
    Parameters,
    Events,
    Reload,
    Code,
    Tests,
    Logic,
    Io,
    Documentation,
    Trends,
    SettingsScreen,
)
