"""The viewport's drawing: the selected resource as a block, its user programs as blocks in
the colours of their states (green RUN, blue RUN (frozen), grey STOP, red ERROR), so that the
state of every program is seen at a glance beside the work area.

The drawing is flat (the XY plane, seen from +Z) and framed to fill the canvas, which is
the strip the docked panels leave free; it is refitted when that strip changes size."""

from __future__ import annotations

import contextlib
import math
import threading

import viser

from frontend.state_rules import state_words
from runtime.contract import protocol as p

COLORS = {
    "RUN": (47, 158, 68),
    "RUN_FREEZE": (34, 139, 230),
    "BKPT": (250, 176, 5),  # stopped at a breakpoint
    "STOP": (134, 142, 150),
    "ERROR": (224, 49, 49),
}
RESOURCE_COLORS = {"RUN": (47, 158, 68), "ERROR STOP": (224, 49, 49)}
OTHER = (230, 119, 0)
SPACING = 1.4
RESOURCE_SIZE = (2.4, 1.0)
PROGRAM_SIZE = (1.2, 0.7)
RESOURCE_Y = 1.2
MARGIN = 0.8  # world units around the drawing
LABEL_HEIGHT = 0.16  # a label's font, in world units, at most
LABEL_INSET = 0.08  # from its block's edges
CHAR_WIDTH = 0.7  # a character's width (with the label's padding) per unit of font height


class PlantView:
    def __init__(self, client: viser.ClientHandle) -> None:
        self._client = client
        self._lock = threading.Lock()
        self._shown: tuple[object, ...] | None = None
        self._nodes: list[viser.SceneNodeHandle] = []
        self._width = RESOURCE_SIZE[0]
        self._canvas: tuple[int, int] | None = None  # known after the browser's first report
        self._active = True  # viser cannot unregister a camera callback: it goes idle instead
        client.scene.set_up_direction("+y")
        client.camera.on_update(self._on_camera)
        # A browser that connected before this login has reported its canvas already; if
        # not, viser asserts ("no report yet") and on_update brings the size later.
        with contextlib.suppress(AssertionError):
            self._canvas = (client.camera.image_width, client.camera.image_height)

    def show(self, resource: str | None, status: p.Status | None) -> None:
        programs = status.programs if status is not None else []
        state = status.state if status is not None else "not logged in"
        key = (resource, state, tuple((x.name, x.state) for x in programs))
        with self._lock:
            if key == self._shown:
                return
            self._shown = key
            self._remove_nodes()
            if resource is not None:
                self._draw(resource, state, programs)
            self._fit()

    def remove(self) -> None:
        with self._lock:
            self._active = False
            self._remove_nodes()

    def _draw(self, resource: str, state: str, programs: list[p.ProgramStatus]) -> None:
        scene = self._client.scene
        block = scene.add_box(
            "/resource",
            color=RESOURCE_COLORS.get(state, OTHER),
            dimensions=(*RESOURCE_SIZE, 0.1),
            position=(0.0, RESOURCE_Y, 0.0),
        )
        _label(scene, "/resource/label", f"{resource}\n{state_words(state)}", RESOURCE_SIZE)
        self._nodes.append(block)  # removing it removes its label
        first = -(len(programs) - 1) * SPACING / 2
        for number, program in enumerate(programs):
            box = scene.add_box(
                f"/programs/{number}",
                color=COLORS.get(program.state, OTHER),
                dimensions=(*PROGRAM_SIZE, 0.1),
                position=(first + number * SPACING, 0.0, 0.0),
            )
            text = f"{program.name}\n{state_words(program.state)}"
            _label(scene, f"/programs/{number}/label", text, PROGRAM_SIZE)
            self._nodes.append(box)
        self._width = max(RESOURCE_SIZE[0], len(programs) * SPACING)

    def _remove_nodes(self) -> None:
        for node in self._nodes:
            node.remove()
        self._nodes.clear()

    def _on_camera(self, camera: viser.CameraHandle) -> None:
        size = (camera.image_width, camera.image_height)
        with self._lock:
            # only a new window size refits: the user may orbit freely
            if self._active and size != self._canvas:
                self._canvas = size
                self._fit()

    def _fit(self) -> None:
        """Look straight at the drawing from a distance at which it fills the canvas."""
        if self._canvas is None:
            return
        width_px, height_px = (max(x, 1) for x in self._canvas)
        drawing_w = self._width + 2 * MARGIN
        drawing_h = RESOURCE_Y + RESOURCE_SIZE[1] / 2 + PROGRAM_SIZE[1] / 2 + 2 * MARGIN
        units_per_px = max(drawing_w / width_px, drawing_h / height_px)
        camera = self._client.camera
        distance = units_per_px * height_px / (2 * math.tan(camera.fov / 2))
        center = (0.0, RESOURCE_Y / 2, 0.0)
        camera.up_direction = (0.0, 1.0, 0.0)
        camera.look_at = center
        camera.position = (center[0], center[1], distance)


def _label(scene: viser.SceneApi, name: str, text: str, size: tuple[float, float]) -> None:
    """A block's label, sized in the drawing's units so that it stays inside its block
    whatever the canvas' size (a label sized in pixels ran out of a block drawn small):
    a long name gets a smaller font."""
    longest = max(len(line) for line in text.splitlines())
    height = min(LABEL_HEIGHT, (size[0] - 2 * LABEL_INSET) / (longest * CHAR_WIDTH))
    scene.add_label(
        name, text, position=_label_at(size), font_size_mode="scene", font_scene_height=height
    )


def _label_at(size: tuple[float, float]) -> tuple[float, float, float]:
    """A label hangs down and right from its anchor: anchor it inside the top left corner."""
    return (-size[0] / 2 + LABEL_INSET, size[1] / 2 - LABEL_INSET, 0.1)
