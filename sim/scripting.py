"""ArduPilot's Lua scripting as the mock runs it: one applet in a real Lua 5.3 interpreter
(lupa's ``lupa.lua53``), scheduled on the mock's simulated clock, with the bindings of
:data:`BINDINGS` and nothing else.

What ArduPilot does, and the mock with it (``libraries/AP_Scripting/lua_scripts.cpp``):

* Each script runs in a sandbox of its own (``lua_scripts::create_sandbox``): the base
  functions, ``math``, ``table``, ``string`` and ``utf8``, and the bindings. The mock leaves
  ``io`` out, and any name it does not provide (a global, a binding, a method of a returned
  object) is an error when read, not a silent nil.
* The loaded chunk is run first, at once (``load_script``: "force the script to be stale");
  each run returns either nothing (the script ends) or the function to run next and the delay
  in milliseconds, from the time it ran (``run_next_script``: ``next_run_ms = millis64() +
  delay``); any other result, or an error, ends the script with a message.
* A run is limited to ``SCR_VM_I_COUNT`` Lua instructions (``reset_loop_overtime``: a count
  hook, 10000 by default): a script that exceeds it "exceeded time limit" and ends.
* Bindings check their argument count and are called as methods (``mission:state()``):
  ``binding_argcheck`` raises "Incorrect number of arguments".

Each binding follows ``libraries/AP_Scripting/docs/docs.lua`` (commit 0004fb5656bad9df): its
name, its arguments and what it returns (:data:`BINDINGS` quotes each).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from lupa import lua53

# Every binding the mock provides: name -> its declaration in docs.lua.
BINDINGS: dict[str, str] = {
    "param:add_table": "param:add_table(table_key, prefix, num_params) -> boolean",
    "param:add_param": "param:add_param(table_key, param_num, name, default_value) -> boolean",
    "param:get": "param:get(name) -> number|nil",
    "param:set": "param:set(name, value) -> boolean",
    "mission:state": "mission:state() -> integer",
    "mission.MISSION_RUNNING": "---@field MISSION_RUNNING number",
    "mission.MISSION_COMPLETE": "---@field MISSION_COMPLETE number",
    "mission.MISSION_STOPPED": "---@field MISSION_STOPPED number",
    "mission:num_commands": "mission:num_commands() -> integer (home included)",
    "mission:get_item": "mission:get_item(index) -> mavlink_mission_item_int_t_ud|nil",
    "mission:get_current_nav_index": "mission:get_current_nav_index() -> integer",
    "mission:set_current_cmd": "mission:set_current_cmd(index) -> boolean",
    "gcs:send_text": "gcs:send_text(severity, text)",
    **{
        f"mavlink_mission_item_int_t_ud:{f}": f"mavlink_mission_item_int_t_ud:{f}() -> number"
        for f in ("seq", "frame", "command", "current", "x", "y", "z")
    },
    **{
        f"mavlink_mission_item_int_t_ud:param{k}": (
            f"mavlink_mission_item_int_t_ud:param{k}() -> number"
        )
        for k in (1, 2, 3, 4)
    },
}
# AP_Mission::mission_state (AP_Mission.h): MISSION_STOPPED 0, MISSION_RUNNING 1,
# MISSION_COMPLETE 2.
MISSION_STOPPED, MISSION_RUNNING, MISSION_COMPLETE = 0, 1, 2
# SCR_VM_I_COUNT's default (AP_Scripting.cpp): Lua instructions a run may take.
VM_STEPS = 10000
# param:add_table's limits (AP_Param::add_table): keys 0..200, prefix plus name at most 16.
TABLE_KEY_MAX = 200
PARAM_NAME_MAX = 16
_ITEM_FIELDS = (
    "seq", "frame", "command", "current", "x", "y", "z", "param1", "param2", "param3", "param4",
)  # fmt: skip
_SANDBOX_BASE = (
    "assert", "error", "ipairs", "next", "pairs", "pcall", "rawequal", "rawget", "rawlen",
    "rawset", "select", "setmetatable", "getmetatable", "tonumber", "tostring", "type", "xpcall",
    "_VERSION", "math", "table", "string", "utf8",
)  # fmt: skip


class ScriptError(RuntimeError):
    """The applet stopped: it failed to load, raised, returned a bad result or ran too long."""


class ScriptVehicle(Protocol):
    """What the bindings read and act on: the autopilot's mission and its messages."""

    def mission_state(self) -> int: ...
    def num_commands(self) -> int: ...
    def get_item(self, index: int) -> Any | None: ...  # a MissionItem
    def current_nav_index(self) -> int: ...
    def set_current_cmd(self, index: int) -> bool: ...
    def send_text(self, severity: int, text: str) -> None: ...
    def parameter(self, name: str) -> float | None: ...


@dataclass
class _Params:
    """Parameters a script adds (param:add_table / add_param) over the vehicle's own."""

    tables: dict[int, tuple[str, int]] = field(default_factory=dict)
    values: dict[str, float] = field(default_factory=dict)


_LUA_SANDBOX = """
local py, base_names, item_fields, vm_steps = ...
local function strict(what, t)
  return setmetatable(t, {__index = function(_, k)
    error(what .. "." .. tostring(k) .. " is not provided by this mock", 2)
  end})
end
local env = {}
for _, name in ipairs(base_names) do env[name] = _G[name] end
local function method(obj, name, fn, nargs)
  obj[name] = function(self, ...)
    if self ~= obj then error(name .. ": call it as a method (obj:" .. name .. ")", 2) end
    if select("#", ...) ~= nargs then error("Incorrect number of arguments", 2) end
    return fn(...)
  end
end
local function item(values)
  local it = {}
  for i, f in ipairs(item_fields) do
    local v = values[i]
    it[f] = function(self, ...)
      if self ~= it then error(f .. ": call it as a method", 2) end
      if select("#", ...) > 0 then error("setting " .. f .. " is not provided by this mock", 2) end
      return v
    end
  end
  return strict("mavlink_mission_item_int_t_ud", it)
end
local mission = {MISSION_STOPPED = 0, MISSION_RUNNING = 1, MISSION_COMPLETE = 2}
method(mission, "state", py.mission_state, 0)
method(mission, "num_commands", py.num_commands, 0)
method(mission, "get_current_nav_index", py.current_nav_index, 0)
method(mission, "set_current_cmd", py.set_current_cmd, 1)
method(mission, "get_item", function(index)
  local values = py.get_item(index)
  if values == nil then return nil end
  return item(values)
end, 1)
local param = {}
method(param, "add_table", py.add_table, 3)
method(param, "add_param", py.add_param, 4)
method(param, "get", py.get, 1)
method(param, "set", py.set, 2)
local gcs = {}
method(gcs, "send_text", py.send_text, 2)
env.mission = strict("mission", mission)
env.param = strict("param", param)
env.gcs = strict("gcs", gcs)
setmetatable(env, {__index = function(_, k)
  error("global '" .. tostring(k) .. "' is not provided by this mock", 2)
end})
local function overtime() error("exceeded time limit", 2) end
local function run(fn)
  debug.sethook(overtime, "", vm_steps)
  local out = table.pack(pcall(fn))
  debug.sethook()
  return out
end
local function load_script(text, name)
  local chunk, why = load(text, "@" .. name, "t", env)
  return chunk or false, why or ""
end
return run, load_script
"""


class ScriptHost:
    """One applet on a vehicle: ``run_due(now_ms)`` runs it whenever its time has come."""

    def __init__(
        self,
        text: str,
        vehicle: ScriptVehicle,
        *,
        name: str = "policy.lua",
        vm_steps: int = VM_STEPS,
        on_error: Callable[[str], None] | None = None,
    ) -> None:
        self.name = name
        self.vehicle = vehicle
        self.on_error = on_error
        self.params = _Params()
        self.jumps: list[tuple[float, int]] = []  # (ms, index) of each set_current_cmd taken
        self.error: str | None = None
        self.runs = 0
        self._now = 0.0
        self.lua = lua53.LuaRuntime(unpack_returned_tuples=True, register_eval=False)
        bridge = self.lua.table_from(self._bridge())
        names = self.lua.table_from(list(_SANDBOX_BASE))
        fields = self.lua.table_from(list(_ITEM_FIELDS))
        self._run, load_script = self.lua.execute(_LUA_SANDBOX, bridge, names, fields, vm_steps)
        chunk, why = load_script(text, name)
        self._fn: Any = chunk
        self.next_run_ms: float | None = 0.0  # the chunk runs at once (module docstring)
        if chunk is False:
            self._stop(f"Lua: Error: {why}")

    # The bindings --------------------------------------------------------------------------
    def _bridge(self) -> Mapping[str, Callable[..., Any]]:
        v = self.vehicle

        def get_item(index: Any) -> Any:
            item = v.get_item(_integer(index, "mission:get_item"))
            if item is None:
                return None
            return self.lua.table_from([getattr(item, f) for f in _ITEM_FIELDS])

        def set_current_cmd(index: Any) -> bool:
            k = _integer(index, "mission:set_current_cmd")
            ok = bool(v.set_current_cmd(k))
            if ok:
                self.jumps.append((self._now, k))
            return ok

        return {
            "mission_state": lambda: int(v.mission_state()),
            "num_commands": lambda: int(v.num_commands()),
            "current_nav_index": lambda: int(v.current_nav_index()),
            "set_current_cmd": set_current_cmd,
            "get_item": get_item,
            "add_table": self._add_table,
            "add_param": self._add_param,
            "get": self._get,
            "set": self._set,
            "send_text": lambda severity, text: v.send_text(
                _integer(severity, "gcs:send_text"), str(text)
            ),
        }

    def _add_table(self, key: Any, prefix: Any, count: Any) -> bool:
        key, count = _integer(key, "param:add_table"), _integer(count, "param:add_table")
        if not 0 <= key <= TABLE_KEY_MAX or not 0 < count or len(str(prefix)) >= PARAM_NAME_MAX:
            return False
        held = self.params.tables.get(key)
        if held is not None and held != (str(prefix), count):
            return False
        self.params.tables[key] = (str(prefix), count)
        return True

    def _add_param(self, key: Any, number: Any, name: Any, default: Any) -> bool:
        table = self.params.tables.get(_integer(key, "param:add_param"))
        number = _integer(number, "param:add_param")
        if table is None or not 1 <= number <= table[1]:
            return False
        full = table[0] + str(name)
        if len(full) > PARAM_NAME_MAX:
            return False
        self.params.values.setdefault(full, float(default))
        return True

    def _get(self, name: Any) -> float | None:
        name = str(name)
        if name in self.params.values:
            return self.params.values[name]
        return self.vehicle.parameter(name)

    def _set(self, name: Any, value: Any) -> bool:
        name = str(name)
        if name not in self.params.values:
            return False  # the mock sets only the script's own parameters
        self.params.values[name] = float(value)
        return True

    def write_parameter(self, name: str, value: float) -> bool:
        """A PARAM_SET from another MAVLink component (the companion's report): False when no
        script added ``name``, as the autopilot refuses an unknown parameter."""
        if name not in self.params.values:
            return False
        self.params.values[name] = float(value)
        return True

    # The scheduler -------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self.next_run_ms is not None

    def run_due(self, now_ms: float) -> None:
        """Run the applet if its time has come at ``now_ms`` (simulated), rescheduling it by the
        delay it returns. A run that fails ends it (``error`` says why, ``on_error`` is told)."""
        while self.next_run_ms is not None and self.next_run_ms <= now_ms:
            self._now = now_ms
            self.runs += 1
            out = self._run(self._fn)
            ok, count = bool(out[1]), int(out["n"])
            if not ok:
                self._stop(f"Lua: {out[2]}")
            elif count == 1:
                self.next_run_ms = None  # returned nothing: the script ends
            elif count != 3:
                self._stop(f"Lua: {self.name} returned bad result count ({count - 1})")
            elif not _is_number(out[3]):
                self._stop(f"Lua: {self.name} did not return a delay")
            elif lua53.lua_type(out[2]) != "function":
                self._stop(f"Lua: {self.name} did not return a function")
            else:
                self._fn = out[2]
                self.next_run_ms = now_ms + max(float(out[3]), 0.0)
                if float(out[3]) <= 0:
                    break  # run again at the next look, not in a loop at the same instant

    def _stop(self, why: str) -> None:
        self.error = why
        self.next_run_ms = None
        if self.on_error is not None:
            self.on_error(why)


def _integer(value: Any, binding: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | float) or value != int(value):
        raise TypeError(f"{binding}: an integer argument, got {value!r}")
    return int(value)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)
