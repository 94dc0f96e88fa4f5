"""The logic of a program or FB instance of a running resource, for a live drawing: which
instances have a body to draw (an SFC chart today), and a chart's geometry with the path
of the variable that holds each live value (a step's `.X` and `.T`, the kept value of a
transition condition: `backend/compiler/resolve.py` `transition_variable`).

Only the runtime's values are shown: nothing here evaluates anything of the source."""

from __future__ import annotations

from dataclasses import dataclass

from backend.compiler import ast
from backend.compiler.parse import parse_source
from backend.compiler.resolve import transition_variable
from backend.engineering.sfc_layout import ChartLayout, chart_layout
from backend.engineering.sources import ConfigurationSources, PouSource


@dataclass(frozen=True)
class LiveChart:
    """An SFC chart of one instance: where its parts stand, and the variables of its values."""

    instance: str  # `Batch`, `Line.filler`
    pou: str
    file: str
    layout: ChartLayout
    steps: dict[str, str]  # step name -> the path of its SFC_STEP variable (`Batch.Fill`)
    transitions: tuple[str, ...]  # by number: the path of the kept condition value

    def watched(self) -> list[str]:
        """Every variable the chart shows."""
        steps = [f"{path}.{member}" for path in self.steps.values() for member in ("X", "T")]
        return steps + list(self.transitions)


class LogicBodies:
    """The POUs of one running configuration parsed for drawing, each once, when first
    asked (a configuration's sources do not change)."""

    def __init__(self, sources: ConfigurationSources) -> None:
        self.sources = sources
        self._parsed: dict[str, ast.Pou | None] = {}

    def kind(self, instance: str) -> str | None:
        """`SFC` when the instance's body is a chart; None when it has nothing to draw.
        Read from the compiled configuration: nothing is parsed for an instance not drawn."""
        unit = self.sources.pou_of(instance)
        return "SFC" if unit is not None and unit.chart is not None and unit.chart.steps else None

    def drawable(self, instances: list[str]) -> list[str]:
        return [instance for instance in instances if self.kind(instance) is not None]

    def chart(self, instance: str) -> LiveChart | None:
        source = self.sources.source_of(instance)
        pou = self._pou(instance)
        if source is None or pou is None or pou.sfc is None or not pou.sfc.steps:
            return None
        return LiveChart(
            instance=instance,
            pou=pou.name,
            file=source.file,
            layout=chart_layout(pou.sfc, source.lines),
            steps={step.name: f"{instance}.{step.name}" for step in pou.sfc.steps},
            transitions=tuple(
                f"{instance}.{transition_variable(n)}" for n in range(len(pou.sfc.transitions))
            ),
        )

    def _pou(self, instance: str) -> ast.Pou | None:
        source = self.sources.source_of(instance)
        if source is None:
            return None
        if source.name.upper() not in self._parsed:
            self._parsed[source.name.upper()] = _parsed(source)
        return self._parsed[source.name.upper()]


def _parsed(source: PouSource) -> ast.Pou | None:
    """The POU alone, parsed from its own lines: positions count from its first line, as
    `source.lines` does (the configuration compiled, so its text parses)."""
    unit = parse_source(source.file, "\n".join(source.lines))
    return next((pou for pou in unit.pous if pou.name.upper() == source.name.upper()), None)
