"""The bus protocol of a resource, version 2: every command it answers and every message it
publishes, one typed dataclass each (docs/protocol.md is the reference for people).

A command class names its wire name, the access level it needs and its reply type; its
fields are its arguments, with their types, ranges and size limits. `decode_request`
checks a whole request (size, nesting, types, ranges, unknown arguments) before anything
else of the runtime sees it; `decode_reply` and `decode` check what a client receives the
same way. On the wire a request is `{"cmd": NAME, "token": TOKEN, ...arguments}`, a reply
`{"ok": true, ...reply fields}` or `{"ok": false, "error": {"code", "message"}}`, all UTF-8
JSON.
"""

from __future__ import annotations

import itertools
import json
import re
import typing
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Annotated, Any, ClassVar, Generic, Literal, TypeVar

from runtime.contract.accounts import ANONYMOUS, NAME_PATTERN, Level
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.contract.keyspace import WATCH_ID_PATTERN, WATCH_ID_RULE
from runtime.contract.outside_json import JsonRefused, read_json
from runtime.contract.refusal import Refusal
from runtime.contract.wire import (
    MAX_DEPTH,
    JsonValue,
    MaxLength,
    Pattern,
    Range,
    decode,
    encode,
)

MAX_REQUEST_BYTES = 64 * 1024
MAX_PATH = 1024  # characters of a variable path
MAX_NAME = 64  # characters of a program or parameter name
MAX_WATCHED = 4096  # variables in one watch request (a larger set comes in several)
MAX_RENAMES = 4096
MAX_MS = 86_400_000  # a day: longer than any parameter or time limit allows
MAX_CHUNK = 24 * 1024  # characters of artifact text per transfer_chunk
MAX_ARTIFACT = 64 * 1024 * 1024  # characters of a whole artifact
MIN_WATCH_PERIOD_MS = 10
MAX_WATCH_PERIOD_MS = 60_000
MAX_EVENTS = 1000  # events per `events` request
# what one session may watch: sets, variables per set, and values per second over its sets
MAX_SETS_PER_SESSION = 8
MAX_SET_VARIABLES = 20_000
MAX_VALUES_PER_SECOND = 200_000
ADMINISTRATOR_PARAMETERS = ("allow_online_settings",)
# recordings (docs/recording.md)
MAX_RECORDED = 4096  # variable paths or `Prefix*` patterns in one record_start
MAX_RECORDING_READ = 48 * 1024  # bytes of a recording file per record_read (base64 in the reply)
MAX_PRE_CYCLES = 100_000
MAX_RECORD_CYCLES = 1_000_000_000


class ResourceState(StrEnum):
    STOP_INVALID = "STOP/INVALID CONFIGURATION"
    STOP_VALID = "STOP/VALID CONFIGURATION"
    RUN = "RUN"
    RUN_UP_STOP = "RUN/UP STOP"  # running, but no user program runs
    ERROR_STOP = "ERROR STOP"


class ProgramState(StrEnum):
    RUN = "RUN"
    RUN_FREEZE = "RUN_FREEZE"  # single step
    BKPT = "BKPT"  # stopped at a breakpoint or a debugging step (docs/debugging.md)
    STOP = "STOP"
    ERROR = "ERROR"


class Quality(StrEnum):
    """How far a watched value can be trusted."""

    LIVE = "live"
    FORCED = "forced"
    STALE = "stale"  # nothing that could change it runs
    DELETED = "deleted"  # gone with a reload
    BAD = "bad"  # an input of a remote device that is lost: it holds its safe value


# ---- argument types

VariableName = Annotated[str, MaxLength(MAX_PATH)]
ProgramName = Annotated[str, MaxLength(MAX_NAME)]
Milliseconds = Annotated[int, Range(1, MAX_MS)]
Crc = Annotated[str, Pattern(r"[0-9A-Fa-f]{8}", "8 hex digits")]
WatchId = Annotated[str, Pattern(WATCH_ID_PATTERN, WATCH_ID_RULE)]  # a chunk of its keys
AccountName = Annotated[str, Pattern(NAME_PATTERN, "1 to 32 of A-Z a-z 0-9 _ -")]
Value = Annotated[Any, JsonValue()]  # a variable's value; checked against its type later
# where a resource runs: its machine's name as the OS gives it, in a set safe to show in a
# terminal or a page (letters, digits, '.', '-', '_'; at most 253 characters, as DNS)
HOST_PATTERN = r"[A-Za-z0-9][A-Za-z0-9._-]{0,252}"
HostName = Annotated[str, Pattern(HOST_PATTERN, "a host name: 1 to 253 of A-Z a-z 0-9 . - _")]
ZenohId = Annotated[str, Pattern(r"[0-9a-f]{1,32}", "a Zenoh session id: 1 to 32 hex digits")]


# ---- publications


@dataclass(frozen=True)
class CycleStatistics:
    count: int
    last_ms: float
    min_ms: float
    max_ms: float
    mean_ms: float
    period_ms: float  # the last period, start to start
    jitter_max_ms: float
    overruns: int  # periods longer than the target cycle time by more than a quarter of it
    watch_deferred: int  # watch-set messages that waited a cycle for the communication slice


@dataclass(frozen=True)
class ProgramStatus:
    name: str
    id: int
    priority: int
    state: ProgramState
    crc: str
    cycles: int
    cpu_cycles_max: int  # most CPU cycles one program cycle spanned
    error: str | None
    paused_at: str | None = None  # in BKPT: where, "tank.st:25 (POU TankControl)"


@dataclass(frozen=True)
class ServerStatus:
    """A server of the resource's field I/O: the served Modbus image (docs/modbus.md), the
    OPC UA server (docs/opcua.md)."""

    host: str
    port: int  # where it listens; 0 while it does not
    listening: bool
    error: str | None  # why it does not listen
    requests: int  # Modbus frames; OPC UA Read and Write calls
    exceptions: int  # Modbus exception responses; OPC UA logins, certificates, writes refused
    writes: int  # write requests taken (Modbus), values written (OPC UA)
    protocol: str = "modbus"  # modbus | opcua
    sessions: int = 0  # OPC UA sessions opened
    certificate: str = ""  # OPC UA: the SHA-1 thumbprint of the server's certificate


ModbusServerStatus = ServerStatus  # its name while Modbus was the only protocol


@dataclass(frozen=True)
class DeviceStatus:
    """A remote I/O device the resource reaches as a client: a Modbus device it polls, an
    OPC UA server it reads or subscribes."""

    name: str
    host: str  # Modbus: its host; OPC UA: its endpoint URL
    port: int
    unit_id: int  # Modbus; 0 for OPC UA
    state: str  # connecting | connected | lost
    last_error: str | None
    requests: int  # Modbus requests sent; OPC UA service calls
    failures: int  # losses (its inputs then hold their safe values)
    round_trip_ms: float  # of the last good poll or call
    protocol: str = "modbus"  # modbus | opcua


@dataclass(frozen=True)
class IoStatus:
    # the Modbus server (as in `servers`): where clients written before OPC UA read it
    server: ServerStatus | None
    devices: list[DeviceStatus]
    servers: list[ServerStatus] = field(default_factory=list)  # every protocol's


@dataclass(frozen=True)
class Status:
    """Published on `status` on every change and at least every second; also the reply of
    every command that changes a state."""

    resource: str
    state: ResourceState
    crc: str | None
    error: str | None  # why the resource is in ERROR STOP
    project: str | None
    cycle: int
    cycle_ms: float
    stats: CycleStatistics
    forcing: bool
    access: str  # "open" (no accounts), "users", or "setup" (no configuration yet)
    start: str | None  # how it starts next (cold, warm) or last started (continued)
    programs: list[ProgramStatus]
    io: IoStatus | None = None  # field I/O; None: the configuration uses none
    # where the runtime runs (None: a runtime before these fields, or a name outside the
    # safe set): the OS's host name and the id of its Zenoh session
    host: HostName | None = None
    zenoh_id: ZenohId | None = None


def safe_host(name: str) -> str | None:
    """A host name as `Status.host` takes it, or None when it is not one (too long, or a
    character outside the safe set): the status must still decode everywhere."""
    return name if re.fullmatch(HOST_PATTERN, name) else None


@dataclass(frozen=True)
class Event:
    """One entry of the event log, published in order on `events` (docs/event-log.md)."""

    seq: int
    time_ns: int
    kind: str
    message: str
    user: str | None
    details: dict[str, Value]


@dataclass(slots=True)
class WatchedValue:
    # not frozen: a client makes 10,000 of these per message of a large set, and a frozen
    # dataclass's __init__ takes twice as long (4.1 against 2.0 ms)
    value: Value
    quality: Quality


@dataclass(frozen=True)
class WatchValues:
    """A watch set's values of one cycle by path, as a client hands them to whoever
    watches (built from the `WatchPublication` and the set's paths)."""

    cycle: int
    values: dict[str, WatchedValue]


# one letter per value in a WatchPublication
QUALITY_LETTERS: dict[str, Quality] = {
    "L": Quality.LIVE,
    "F": Quality.FORCED,
    "S": Quality.STALE,
    "D": Quality.DELETED,
    "B": Quality.BAD,
}
LETTER_OF_QUALITY: dict[Quality, str] = {q: letter for letter, q in QUALITY_LETTERS.items()}


@dataclass(frozen=True)
class WatchPublication:
    """A watch set's values of one cycle, published on `watch/<id>` once per its period:
    the values in the order of the set's paths (the `watch` reply names them), and one
    letter per value for its quality (`QUALITY_LETTERS`). Paths are not repeated in every
    message: for 10,000 values that made the message five times longer and its encoding,
    which holds the interpreter, ten times slower. `revision` counts the set's changes, so
    that values of an older set are never taken for a newer one's."""

    cycle: int
    revision: int
    values: list[Value]
    qualities: Annotated[str, Pattern(r"[LFSDB]*", "one of L F S D B per value")]


# ---- replies


@dataclass(frozen=True)
class Done:
    """The reply of a command with nothing to report but that it was done."""


@dataclass(frozen=True)
class StatusReply:
    status: Status


@dataclass(frozen=True)
class ValuesReply:
    values: dict[str, Value]
    cycle: int


@dataclass(frozen=True)
class IoPoint:
    """A variable on the field bus with what is on the wire now."""

    source: str  # "server" (the served Modbus image), "OPC UA server", or a device's name
    variable: str
    location: str  # its direct address; "" for an OPC UA server's variable
    type: str
    area: str  # Modbus: coil | discrete_input | input_register | holding_register
    address: int  # Modbus
    writable: bool  # a client may write it (served points)
    value: Value  # served: as served (safe in STOP); device inputs: as delivered
    quality: str  # good | bad (its device is lost) | safe (the served output is safe)
    protocol: str = "modbus"  # modbus | opcua
    place: str = ""  # where on the bus, as text: `holding_register 1024`, an OPC UA node id


@dataclass(frozen=True)
class IoReply:
    io: IoStatus | None
    points: list[IoPoint]


@dataclass(frozen=True)
class VariableInfo:
    path: str
    type: str


@dataclass(frozen=True)
class VariablesReply:
    variables: list[VariableInfo]


@dataclass(frozen=True)
class EventsReply:
    events: list[Event]
    # the long-term log only: each entry's `prev`, the SHA-256 of the entry before it as
    # written (docs/event-log.md), so that a client can check the chain itself
    prev: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class ForceInfo:
    variable: str
    level: str  # "global" or a program
    value: Value
    switch: bool
    active: bool


@dataclass(frozen=True)
class ForcingState:
    started: list[str]  # levels where forcing runs: "" for global, else a program
    remaining_ms: dict[str, float | None]  # per started level ("global" for "")
    entries: list[ForceInfo]


@dataclass(frozen=True)
class ForcingReply:
    forcing: ForcingState


@dataclass(frozen=True)
class ParametersReply:
    resource: ResourceConfig
    programs: list[ProgramConfig]


@dataclass(frozen=True)
class WatchReply:
    id: str
    variables: list[str]  # canonical paths, in the order asked
    revision: int = 1  # of the set, as its publications carry it


@dataclass(frozen=True)
class UnwatchReply:
    dropped: bool


@dataclass(frozen=True)
class WatchesReply:
    watches: list[str]


@dataclass(frozen=True)
class TransferBeginReply:
    max_chunk: int


@dataclass(frozen=True)
class TransferChunkReply:
    received: int


@dataclass(frozen=True)
class VariableChange:
    path: str  # in the new configuration (the old one for `deleted`)
    action: str  # kept | converted | initialised | new | deleted
    old_type: str | None
    new_type: str | None
    source: str | None = None  # the old path a value comes from (differs after a rename)
    reason: str = ""


@dataclass(frozen=True)
class Hazard:
    kind: str  # active-step-deleted | initial-step-renamed | timed-qualifier-deleted | ...
    instance: str  # the program or FB instance whose chart is affected
    message: str


@dataclass(frozen=True)
class ProgramChanges:
    added: list[str]
    removed: list[str]
    changed: list[str]


@dataclass(frozen=True)
class ReloadPlanInfo:
    """What a reload would do to every value, and whether it is possible: the preview."""

    old_crc: str
    new_crc: str
    possible: bool
    refusals: list[str]  # why this change needs STOP and a download
    hazards: list[Hazard]
    programs: ProgramChanges
    summary: dict[str, int]  # values kept, converted, initialised, new, deleted
    changes: list[VariableChange]
    estimate_us: float  # extra time of the switch-over between two cycles


@dataclass(frozen=True)
class ReloadPlanReply:
    plan: ReloadPlanInfo


@dataclass(frozen=True)
class ReloadOutcome:
    old_crc: str
    new_crc: str
    pause_us: float  # how long the cycles stood still for the switch-over
    carried: int  # values carried over


@dataclass(frozen=True)
class ReloadReply:
    reload: ReloadOutcome
    status: Status


@dataclass(frozen=True)
class RecordingFile:
    name: str  # `<recording id>-<n>.mcap`, in the resource's state folder
    size: int  # bytes so far


@dataclass(frozen=True)
class RecordingInfo:
    """One recording of the resource (docs/recording.md)."""

    id: str
    state: Literal["waiting", "recording", "done", "failed"]  # waiting: for its trigger
    variables: int  # elementary variables recorded
    all_inputs: bool
    cycles: int  # CPU cycles written so far
    dropped: int  # cycles lost because the writer fell behind (the queue was full)
    started_ns: int  # wall-clock time the recording was started (Unix ns)
    files: list[RecordingFile]
    error: str | None = None  # why it failed or was cut short
    trigger_cycle: int | None = None  # the CPU cycle the trigger fired in
    # known from its files only (the runtime restarted since): its drops are not known
    from_files: bool = False


@dataclass(frozen=True)
class RecordingReply:
    recording: RecordingInfo


@dataclass(frozen=True)
class RecordingsReply:
    recordings: list[RecordingInfo]


@dataclass(frozen=True)
class RecordingChunk:
    data: str  # base64 of the bytes from `offset`
    offset: int
    size: int  # of the whole file now (it may still grow)


@dataclass(frozen=True)
class LoginChallenge:
    nonce: str  # the client's nonce, extended by the resource's part
    salt: str  # base64
    n: int  # scrypt cost parameters of the verifier
    r: int
    p: int
    publication_key: str  # base64 Ed25519 public key of the resource
    # base64: that key's signature of scram.challenge_message (the client's nonce in it)
    signature: str


@dataclass(frozen=True)
class LoginReply:
    token: str
    user: str
    level: str  # one of accounts.LEVELS
    server_signature: str  # base64: the resource's proof that it holds the verifier
    publication_key: str  # base64 Ed25519 public key: every publication is signed with it


# ---- the commands

R = TypeVar("R")
COMMANDS: dict[str, type[Command[Any]]] = {}  # by wire name


class Command(Generic[R]):
    """A command; its dataclass fields are its arguments. A subclass gives its wire name and
    the level it needs: `class Start(Command[StatusReply], name="start", level="operator")`;
    its reply type is the type argument. Level None: no session needed (the login)."""

    NAME: ClassVar[str]
    LEVEL: ClassVar[Level | None]
    REPLY: ClassVar[type[Any]]

    def __init_subclass__(cls, /, name: str, level: Level | None, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        (base,) = (b for b in cls.__orig_bases__ if typing.get_origin(b) is Command)  # type: ignore[attr-defined]
        cls.NAME, cls.LEVEL, cls.REPLY = name, level, typing.get_args(base)[0]
        COMMANDS[name] = cls

    def level(self) -> Level | None:
        """The level this request needs (some arguments need more than the command)."""
        return self.LEVEL


Nonce = Annotated[str, Pattern(r"[A-Za-z0-9_=-]{16,96}", "16 to 96 characters of base64url")]


@dataclass(frozen=True)
class LoginBegin(Command[LoginChallenge], name="login_begin", level=None):
    """The first step of a login (runtime/contract/scram.py): the user and a fresh nonce."""

    user: AccountName
    nonce: Nonce


@dataclass(frozen=True)
class Login(Command[LoginReply], name="login", level=None):
    """The second step: the proof that the client knows the password, for the nonce of the
    challenge. Every later request carries `token`, a sequence number `seq` and, as its
    Zenoh attachment, the MAC of its bytes with the session key."""

    user: AccountName
    nonce: Nonce
    proof: Annotated[str, Pattern(r"[A-Za-z0-9+/=]{44}", "a base64 SHA-256 proof")]


@dataclass(frozen=True)
class Logout(Command[Done], name="logout", level="read"):
    """Ends the session of the request's token: a request of that session like any other
    (its MAC and sequence number), so that a token seen on the bus ends nothing."""


@dataclass(frozen=True)
class GetStatus(Command[StatusReply], name="status", level="read"):
    pass


@dataclass(frozen=True)
class GetValues(Command[ValuesReply], name="values", level="read"):
    """Every variable at once, for tools; live views use watch sets."""


@dataclass(frozen=True)
class GetVariables(Command[VariablesReply], name="variables", level="read"):
    pass


@dataclass(frozen=True)
class GetIo(Command[IoReply], name="io", level="read"):
    """The Modbus server and devices with every mapped point and its value now."""


@dataclass(frozen=True)
class GetParameters(Command[ParametersReply], name="parameters", level="read"):
    pass


@dataclass(frozen=True)
class GetForcing(Command[ForcingReply], name="forcing", level="read"):
    pass


@dataclass(frozen=True)
class GetEvents(Command[EventsReply], name="events", level="read"):
    """The short-term (or long-term) event log after sequence number `after`, oldest
    first; the long-term entries come with their `prev`."""

    after: Annotated[int, Range(0, None)] = 0
    limit: Annotated[int, Range(1, MAX_EVENTS)] = 200
    log: Literal["short", "long"] = "short"


@dataclass(frozen=True)
class Watch(Command[WatchReply], name="watch", level="read"):
    """Register (or, with `append`, extend) watch set `id`: its values come on `watch/<id>`
    while the client holds the liveliness token `watchers/<id>`."""

    id: WatchId
    variables: Annotated[list[VariableName], MaxLength(MAX_WATCHED)]
    period_ms: Annotated[int, Range(MIN_WATCH_PERIOD_MS, MAX_WATCH_PERIOD_MS)] = 100
    append: bool = False


@dataclass(frozen=True)
class Unwatch(Command[UnwatchReply], name="unwatch", level="read"):
    id: WatchId


@dataclass(frozen=True)
class GetWatches(Command[WatchesReply], name="watches", level="read"):
    pass


@dataclass(frozen=True)
class Start(Command[StatusReply], name="start", level="operator"):
    pass


@dataclass(frozen=True)
class Stop(Command[StatusReply], name="stop", level="operator"):
    pass


@dataclass(frozen=True)
class ResetStats(Command[StatusReply], name="reset_stats", level="operator"):
    pass


@dataclass(frozen=True)
class StartProgram(Command[StatusReply], name="start_program", level="operator"):
    program: ProgramName


@dataclass(frozen=True)
class StopProgram(Command[StatusReply], name="stop_program", level="operator"):
    program: ProgramName


@dataclass(frozen=True)
class Force(Command[StatusReply], name="force", level="operator"):
    """Prepare a force value and its switch; it acts while forcing runs at its level."""

    variable: VariableName
    value: Value
    switch: bool = True


@dataclass(frozen=True)
class Unforce(Command[StatusReply], name="unforce", level="operator"):
    variable: VariableName


@dataclass(frozen=True)
class StartForcing(Command[StatusReply], name="start_forcing", level="operator"):
    """Start forcing at a level: one program's (local), or global without `program`."""

    program: ProgramName | None = None
    timeout_ms: Milliseconds | None = None


@dataclass(frozen=True)
class StopForcing(Command[StatusReply], name="stop_forcing", level="operator"):
    program: ProgramName | None = None


@dataclass(frozen=True)
class Init(Command[StatusReply], name="init", level="read-write"):
    """Leave ERROR STOP for STOP; the next start is a cold start."""


@dataclass(frozen=True)
class ColdStart(Command[StatusReply], name="cold_start", level="read-write"):
    pass


@dataclass(frozen=True)
class Step(Command[StatusReply], name="step", level="read-write"):
    """In STOP: one CPU cycle of every program."""


@dataclass(frozen=True)
class Freeze(Command[StatusReply], name="freeze", level="read-write"):
    program: ProgramName


@dataclass(frozen=True)
class Unfreeze(Command[StatusReply], name="unfreeze", level="read-write"):
    program: ProgramName


@dataclass(frozen=True)
class StepProgram(Command[StatusReply], name="step_program", level="read-write"):
    """One program cycle of a frozen program; its time advances by `interval_ms` (default:
    the target cycle time)."""

    program: ProgramName
    interval_ms: Milliseconds | None = None


@dataclass(frozen=True)
class Write(Command[StatusReply], name="write", level="read-write"):
    """Write a value once (not forcing)."""

    variable: VariableName
    value: Value


@dataclass(frozen=True)
class SetParameter(Command[StatusReply], name="set_parameter", level="read-write"):
    name: Annotated[str, MaxLength(MAX_NAME)]
    value: bool | int | str

    def level(self) -> Level | None:
        return "administrator" if self.name in ADMINISTRATOR_PARAMETERS else self.LEVEL


@dataclass(frozen=True)
class TransferBegin(Command[TransferBeginReply], name="transfer_begin", level="read-write"):
    """Announce an artifact text of `size` characters and CRC `crc` (docs/reload.md)."""

    size: Annotated[int, Range(1, MAX_ARTIFACT)]
    crc: Crc


@dataclass(frozen=True)
class TransferChunk(Command[TransferChunkReply], name="transfer_chunk", level="read-write"):
    offset: Annotated[int, Range(0, MAX_ARTIFACT)]
    data: Annotated[str, MaxLength(MAX_CHUNK)]


@dataclass(frozen=True)
class Load(Command[StatusReply], name="load", level="read-write"):
    """Download the transferred artifact (STOP only); a cold start follows."""


Renames = Annotated[dict[str, VariableName], MaxLength(MAX_RENAMES)]  # NEW name -> OLD name


@dataclass(frozen=True)
class ReloadPreview(Command[ReloadPlanReply], name="reload_preview", level="read-write"):
    """The reload plan of the transferred artifact against the running state."""

    renames: Renames = field(default_factory=dict)


@dataclass(frozen=True)
class Reload(Command[ReloadReply], name="reload", level="read-write"):
    """Online change to the transferred artifact. `watchdog_ms` and `target_cycle_ms` raise
    the budget for this reload; `expected_crc` is the configuration the user previewed
    against (refused with `changed` when the resource runs another)."""

    renames: Renames = field(default_factory=dict)
    watchdog_ms: Milliseconds | None = None
    target_cycle_ms: Milliseconds | None = None
    expected_crc: Crc | None = None


RecordingId = Annotated[str, Pattern(r"[A-Za-z0-9_-]{1,64}", "1 to 64 of A-Z a-z 0-9 _ -")]
RecordingFileName = Annotated[
    str, Pattern(r"[A-Za-z0-9_-]{1,64}-[0-9]{1,6}\.mcap", "a file name of record_list")
]


@dataclass(frozen=True)
class Trigger:
    """Start writing when `variable op value` becomes true (it was false the cycle before);
    a BOOL variable alone is `variable = TRUE`."""

    variable: VariableName
    op: Literal["=", "<>", "<", "<=", ">", ">="] = "="
    value: Value = True


@dataclass(frozen=True)
class RecordStart(Command[RecordingReply], name="record_start", level="operator"):
    """Record `variables` (paths, or `Prefix*` for every variable whose path starts so) every
    CPU cycle into MCAP files in the state folder. With `all_inputs`, also everything
    the programs take from outside, for `padt replay`. With a trigger, `pre_cycles` cycles
    before it are kept too. It ends after `cycles` CPU cycles or `seconds` (counted from the
    trigger when there is one) or at record_stop; a file is closed and the next one begun
    every `rotate_mb` megabytes or `rotate_s` seconds."""

    variables: Annotated[list[VariableName], MaxLength(MAX_RECORDED)]
    all_inputs: bool = False
    trigger: Trigger | None = None
    pre_cycles: Annotated[int, Range(0, MAX_PRE_CYCLES)] = 0
    cycles: Annotated[int, Range(1, MAX_RECORD_CYCLES)] | None = None
    seconds: Annotated[int, Range(1, 7 * 86_400)] | None = None
    rotate_mb: Annotated[int, Range(1, 4096)] = 256
    rotate_s: Annotated[int, Range(1, 7 * 86_400)] | None = None
    id: RecordingId | None = None  # chosen by the resource when not given


@dataclass(frozen=True)
class RecordStop(Command[RecordingReply], name="record_stop", level="operator"):
    id: RecordingId


@dataclass(frozen=True)
class RecordList(Command[RecordingsReply], name="record_list", level="read"):
    """The recordings in the state folder, the running ones first."""


@dataclass(frozen=True)
class RecordRead(Command[RecordingChunk], name="record_read", level="read"):
    """Up to `length` bytes of a recording file from `offset` (for a download)."""

    file: RecordingFileName
    offset: Annotated[int, Range(0, None)] = 0
    length: Annotated[int, Range(1, MAX_RECORDING_READ)] = MAX_RECORDING_READ


@dataclass(frozen=True)
class RecordDelete(Command[RecordingsReply], name="record_delete", level="operator"):
    """Delete a recording that has ended, with its files."""

    id: RecordingId


# ---- debugging in the code (docs/debugging.md)

MAX_BREAKPOINTS = 256  # in one file
MAX_EXPRESSION = 512  # characters of a condition or a logged expression
MAX_LOGGED = 16  # expressions one logpoint records
MIN_DEBUG_TIMEOUT_S, MAX_DEBUG_TIMEOUT_S = 5, 3600
SourceFile = Annotated[str, MaxLength(MAX_PATH)]  # as the artifact names it: "tank.st"
SourceLine = Annotated[int, Range(1, 10_000_000)]
Expression = Annotated[str, MaxLength(MAX_EXPRESSION)]
DebugStepKind = Literal["over", "into", "out", "cycle"]


@dataclass(frozen=True)
class BreakpointSpec:
    """A breakpoint (or, with `log`, a logpoint) at a line of one file."""

    line: SourceLine
    program: ProgramName | None = None  # only while this program runs
    instance: VariableName | None = None  # only in this FB instance ("Main.valve1")
    condition: Expression | None = None  # an ST boolean expression, checked at the line
    hit_count: Annotated[int, Range(1, 1_000_000_000)] | None = None  # stop from this hit on
    log: Annotated[list[Expression], MaxLength(MAX_LOGGED)] | None = None  # never stops


@dataclass(frozen=True)
class ArmedBreakpoint:
    id: int
    file: str
    requested: int  # the line asked for
    line: int  # the statement it stands at: the first at or after `requested`; 0 if none
    verified: bool  # False: not armed, `message` says why
    message: str | None
    spec: BreakpointSpec
    hits: int


@dataclass(frozen=True)
class DebugPause:
    """Where a program in BKPT stands: before the statement at `file:line`, or (line 0) at
    the end of its program cycle."""

    program: str
    pou: str
    file: str
    line: int
    reason: str  # "breakpoint", "step", "run to", "cycle end"
    breakpoint: int | None  # the id of the breakpoint that was hit


@dataclass(frozen=True)
class DebugState:
    breakpoints: list[ArmedBreakpoint]
    paused: DebugPause | None
    timeout_s: int  # the paused program continues after this long without a debug command
    silent_s: float  # how long no debug command came


@dataclass(frozen=True)
class DebugReply:
    debug: DebugState


@dataclass(frozen=True)
class DebugFrame:
    """One frame of the call stack of a program in BKPT, innermost first."""

    index: int
    name: str  # "TankControl", "Counter.Bump", "Twice"
    kind: str  # "program", "function block", "method", "function", "action"
    instance: str | None  # the path of the instance whose code runs ("Main.a")
    pou: str
    file: str
    line: int


@dataclass(frozen=True)
class StackReply:
    frames: list[DebugFrame]


@dataclass(frozen=True)
class DebugVariable:
    name: str
    type: str  # the IEC type where the artifact knows it
    value: Value  # a plain value; null for a structure, an array or an instance
    path: str | None  # the variable's path for `write` and `force` (null: a local)
    children: bool  # members or elements: ask `debug_variables` for them


@dataclass(frozen=True)
class DebugVariablesReply:
    variables: list[DebugVariable]


@dataclass(frozen=True)
class DebugGet(Command[DebugReply], name="debug", level="read"):
    """The breakpoints and where a program stands; `keep` (read-write) tells the resource
    the debugging client is still there."""

    keep: bool = False

    def level(self) -> Level | None:
        return "read-write" if self.keep else self.LEVEL


@dataclass(frozen=True)
class DebugSet(Command[DebugReply], name="debug_set", level="read-write"):
    """The breakpoints and logpoints of one file, in place of those it had."""

    file: SourceFile
    breakpoints: Annotated[list[BreakpointSpec], MaxLength(MAX_BREAKPOINTS)]


@dataclass(frozen=True)
class DebugClear(Command[DebugReply], name="debug_clear", level="read-write"):
    """Every breakpoint and logpoint gone; a program in BKPT continues."""


@dataclass(frozen=True)
class DebugContinue(Command[DebugReply], name="debug_continue", level="read-write"):
    program: ProgramName


@dataclass(frozen=True)
class DebugStep(Command[DebugReply], name="debug_step", level="read-write"):
    """One statement (over calls, into them, out of the current one), or to the end of the
    program cycle (`cycle`)."""

    program: ProgramName
    kind: DebugStepKind = "over"


@dataclass(frozen=True)
class DebugRunTo(Command[DebugReply], name="debug_run_to", level="read-write"):
    """Continue until the statement at `file:line` (the cursor)."""

    program: ProgramName
    file: SourceFile
    line: SourceLine


@dataclass(frozen=True)
class DebugStack(Command[StackReply], name="debug_stack", level="read"):
    program: ProgramName


@dataclass(frozen=True)
class DebugVariables(Command[DebugVariablesReply], name="debug_variables", level="read"):
    """The variables of a frame of a program in BKPT; `path`, a variable of the frame that
    has children ("a", "a.sub", "arr[2]"): its members or elements instead."""

    program: ProgramName
    frame: Annotated[int, Range(0, 10_000)] = 0
    path: Annotated[str, MaxLength(MAX_PATH)] = ""


@dataclass(frozen=True)
class DebugOptions(Command[DebugReply], name="debug_options", level="read-write"):
    """How long a debugging client may stay silent before the program continues by itself
    (not `timeout_s`: clients take that name for how long they wait for a reply)."""

    silent_s: Annotated[int, Range(MIN_DEBUG_TIMEOUT_S, MAX_DEBUG_TIMEOUT_S)]


# ---- requests and replies on the wire

# the level each command needs (the login's two steps need none)
COMMAND_LEVELS: dict[str, Level] = {
    name: kind.LEVEL for name, kind in COMMANDS.items() if kind.LEVEL is not None
}


@dataclass(frozen=True)
class Request:
    """A decoded request: the command, its session token and sequence number, the source
    the sender named (its Zenoh session; `anonymous` when it named none), and what the
    session's MAC covers (the request's bytes) with the MAC itself."""

    command: Command[Any]
    token: str | None
    source: str = ANONYMOUS
    seq: int | None = None
    signed: bytes = b""
    mac: bytes | None = None


def decode_request(payload: bytes, source: str = ANONYMOUS, mac: bytes | None = None) -> Request:
    """A whole request checked: size, JSON, nesting, the command and every argument.
    Refusal `too_large`, `bad_request` or `unknown_command` otherwise."""
    if len(payload) > MAX_REQUEST_BYTES:
        raise Refusal("too_large", f"request larger than {MAX_REQUEST_BYTES} bytes")
    try:
        data = read_json(payload, "the request", MAX_REQUEST_BYTES, MAX_DEPTH)
    except JsonRefused as exc:
        raise Refusal("bad_request", str(exc)) from None
    if not isinstance(data, dict) or not isinstance(data.get("cmd"), str):
        raise Refusal("bad_request", 'request must be an object with a "cmd" text')
    name = data.pop("cmd")
    kind = COMMANDS.get(name)
    if kind is None:
        raise Refusal("unknown_command", f"unknown command '{name[:MAX_NAME]}'")
    token = data.pop("token", None)
    if token is not None and (not isinstance(token, str) or len(token) > 128):
        raise Refusal("bad_request", '"token" must be a session token')
    seq = data.pop("seq", None)
    if seq is not None and (isinstance(seq, bool) or not isinstance(seq, int) or seq < 1):
        raise Refusal("bad_request", '"seq" must be a positive integer')
    if mac is not None and len(mac) > 64:
        raise Refusal("bad_request", "the MAC is too long")
    return Request(decode(kind, data), token, source, seq, payload, mac)


def encode_request(command: Command[Any], token: str | None, seq: int | None = None) -> bytes:
    session = {"token": token, "seq": seq} if token is not None else {}
    return json.dumps({"cmd": command.NAME, **session, **encode(command)}).encode()


def encode_reply(reply: Any) -> bytes:
    """The reply as JSON, the same bytes as one `json.dumps`; a large object field (the
    100,000 values of `values`) is encoded a batch of entries at a time: one encoder call
    holds the GIL the cycle thread needs for as long as it runs."""
    fields = {"ok": True, **encode(reply)}
    if not any(type(v) is dict and len(v) > _REPLY_BATCH for v in fields.values()):
        return json.dumps(fields).encode()
    parts = []
    for key, value in fields.items():
        if type(value) is dict and len(value) > _REPLY_BATCH:
            # never a list of every entry: making one (100,000 pairs) was itself one call
            # that held the GIL for 6-16 ms
            entries = iter(value.items())
            batches = []
            while batch := dict(itertools.islice(entries, _REPLY_BATCH)):
                batches.append(json.dumps(batch)[1:-1])
            text = "{" + ", ".join(batches) + "}"
        else:
            text = json.dumps(value)
        parts.append(f"{json.dumps(key)}: {text}")
    return ("{" + ", ".join(parts) + "}").encode()


_REPLY_BATCH = 2_000


def encode_list(values: list[Any]) -> str:
    """The list as JSON (no NaN: ValueError), the same text as one `json.dumps`, encoded
    a batch of items at a time for the reason `encode_reply` gives (10,000 watched
    values are 1.6 ms in one encoder call)."""
    if len(values) <= _REPLY_BATCH:
        return json.dumps(values, allow_nan=False)
    batches = (
        json.dumps(values[n : n + _REPLY_BATCH], allow_nan=False)[1:-1]
        for n in range(0, len(values), _REPLY_BATCH)
    )
    return "[" + ", ".join(batches) + "]"


def encode_refusal(refusal: Refusal) -> bytes:
    return json.dumps({"ok": False, "error": refusal.as_json()}).encode()


def decode_reply(command: Command[R], payload: bytes) -> R:
    """A resource's reply to `command`, checked: the reply, or its refusal raised. A reply
    that is not what the protocol says is refused as `bad_reply`."""
    try:
        data = read_json(payload, "the reply", len(payload), max_depth=None)  # decode checks
    except JsonRefused as exc:
        raise Refusal("bad_reply", str(exc)) from None
    if not isinstance(data, dict) or not isinstance(data.get("ok"), bool):
        raise Refusal("bad_reply", 'a reply is an object with "ok"')
    ok = data.pop("ok")
    if not ok:
        error = data.get("error")
        if not isinstance(error, dict):
            raise Refusal("bad_reply", 'a refusal has an "error" object')
        raise Refusal(str(error.get("code", "unknown")), str(error.get("message", "")))
    try:
        reply: R = decode(command.REPLY, data)
    except Refusal as wrong:
        raise Refusal("bad_reply", f"reply to {command.NAME}: {wrong.message}") from None
    return reply


def decode_publication(kind: type[R], payload: bytes) -> R:
    """A publication (Status, Event, WatchValues) checked; Refusal `bad_reply` otherwise."""
    try:
        return decode(kind, read_json(payload, f"a {kind.__name__}", len(payload), max_depth=None))
    except JsonRefused as exc:
        raise Refusal("bad_reply", str(exc)) from None
    except Refusal as wrong:
        raise Refusal("bad_reply", f"{kind.__name__}: {wrong.message}") from None


def pieces(text: str, size: int = MAX_CHUNK) -> list[tuple[int, str]]:
    """An artifact text in transfer chunks: (offset, data)."""
    return [(offset, text[offset : offset + size]) for offset in range(0, len(text), size)]
