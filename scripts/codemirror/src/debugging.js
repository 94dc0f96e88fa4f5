// Debugging in the editor: breakpoints in a gutter left of the line numbers (a click toggles
// one, a right-click edits its condition, hit count or logged expressions), the line where a
// program stands in BKPT lit with an arrow, and the Debug panel below the editor: where the
// program stands, its call stack, the variables of the chosen frame, the steps.
// The server (frontend/editor/debugging.py) sends the resource's debug state as one "debug"
// message whenever it changes; the page sends a file's breakpoints ("breakpoints", all of
// them: they replace the file's) and each control of the panel ("debug").
import { StateEffect, StateField, RangeSetBuilder } from "@codemirror/state";
import { EditorView, Decoration, gutter, GutterMarker } from "@codemirror/view";
import { el, BUTTON } from "./dom.js";

const PENDING_MS = 5000; // a breakpoint set in the page shows as asked until the server says
const CELL = "padding:2px 8px;white-space:nowrap";

export const debugChanged = StateEffect.define();
export const setLit = StateEffect.define();

// the stopped line (and a frame's line when another frame is chosen), drawn in the text
export const litField = StateField.define({
  create: () => Decoration.none,
  update(value, tr) {
    value = value.map(tr.changes);
    for (const e of tr.effects) if (e.is(setLit)) value = e.value;
    return value;
  },
  provide: (f) => EditorView.decorations.from(f),
});

export function litDecorations(doc, lines) {
  const builder = new RangeSetBuilder();
  for (const [line, kind] of [...lines].sort((a, b) => a[0] - b[0])) {
    if (line < 1 || line > doc.lines) continue;
    const from = doc.line(line).from;
    builder.add(from, from, Decoration.line({ class: `padt-${kind}-line`, attributes: { "data-lit": kind } }));
  }
  return builder.finish();
}

class DebugMarker extends GutterMarker {
  constructor(bp, arrow) {
    super();
    this.bp = bp;
    this.arrow = arrow;
  }
  eq(other) {
    return JSON.stringify([this.bp, this.arrow]) === JSON.stringify([other.bp, other.arrow]);
  }
  toDOM() {
    const box = el("span", { style: "display:contents" });
    const b = this.bp;
    if (!b) box.append(el("span", { class: "padt-bp-none" })); // the arrow stays in its column
    else {
      const kinds = ["padt-bp"];
      if (b.log) kinds.push("padt-bp-log");
      if (b.condition || b.hit_count) kinds.push("padt-bp-cond");
      if (!b.verified) kinds.push("padt-bp-unverified");
      if (b.pending) kinds.push("padt-bp-pending");
      box.append(el("span", {
        class: kinds.join(" "), "data-bp-line": String(b.shown), "data-bp": b.pending ? "pending" : b.verified ? "verified" : "unverified",
        title: describe(b),
      }));
    }
    if (this.arrow) {
      const title = this.arrow === "top" ? "The program stands here (before this statement)" : "The chosen frame's line";
      box.append(el("span", { class: `padt-arrow${this.arrow === "frame" ? " padt-arrow-frame" : ""}`, "data-arrow": this.arrow, title }));
    }
    return box;
  }
}

function describe(b) {
  if (!b.verified) return b.message || "not armed";
  const parts = [b.log ? `Logpoint: ${b.log.join(", ")}` : "Breakpoint"];
  if (b.condition) parts.push(`when ${b.condition}`);
  if (b.hit_count) parts.push(`from hit ${b.hit_count}`);
  if (b.requested && b.line && b.requested !== b.line) parts.push(`(asked at line ${b.requested}, stands at the next statement)`);
  if (b.hits) parts.push(`${b.hits} hit${b.hits === 1 ? "" : "s"}`);
  return parts.join(" ") + " — right-click to edit";
}

class Spacer extends GutterMarker {
  toDOM() {
    return el("span", { style: "display:inline-block;width:21px" }); // a dot and an arrow
  }
}

export function debugGutter(editor) {
  const lineOf = (view, block) => view.state.doc.lineAt(block.from).number;
  return gutter({
    class: "padt-debug-gutter",
    lineMarker: (view, block) => editor.debug.marker(lineOf(view, block)),
    lineMarkerChange: (u) => u.transactions.some((tr) => tr.effects.some((e) => e.is(debugChanged))),
    initialSpacer: () => new Spacer(),
    domEventHandlers: {
      mousedown: (view, block, event) => {
        if (event.button !== 0) return false;
        event.preventDefault();
        editor.debug.toggle(lineOf(view, block));
        return true;
      },
      contextmenu: (view, block, event) => {
        event.preventDefault();
        editor.debug.edit(lineOf(view, block));
        return true;
      },
    },
  });
}

// "a, LIMIT(0, b, 10), c" -> three expressions: commas inside brackets do not separate
export function splitExpressions(text) {
  const found = [];
  let depth = 0;
  let start = 0;
  for (let i = 0; i <= text.length; i++) {
    const c = text[i];
    if (c === "(" || c === "[") depth += 1;
    else if (c === ")" || c === "]") depth = Math.max(0, depth - 1);
    else if ((c === "," && depth === 0) || i === text.length) {
      const part = text.slice(start, i).trim();
      if (part) found.push(part);
      start = i + 1;
    }
  }
  return found;
}

const ACTIONS = [
  ["continue", "Continue", "F5"],
  ["over", "Step over", "F10"],
  ["into", "Step into", "F11"],
  ["out", "Step out", "Shift+F11"],
  ["cycle", "Finish cycle", ""],
  ["run_to", "Run to cursor", ""],
];

export class DebugPanel {
  constructor(editor) {
    this.editor = editor;
    this.state = { on: false, why: "", breakpoints: [], paused: null };
    this.local = new Map(); // file -> {items, at}: set in the page, not yet answered
    this.pauseKey = "";
  }

  // ---- what the server says
  receive(m) {
    this.state = m;
    const ed = this.editor;
    for (const [file, mine] of this.local) {
      const theirs = this.serverItems(file).map((b) => b.line).sort().join();
      const asked = mine.items.map((b) => b.line).sort().join();
      if (theirs === asked || Date.now() - mine.at > PENDING_MS) this.local.delete(file);
    }
    const p = m.paused;
    const key = p ? `${m.resource}|${p.program}|${p.file}|${p.line}|${p.reason}` : "";
    const entered = key && key !== this.pauseKey;
    this.pauseKey = key;
    if (entered) {
      // the panel comes to the front, tall enough for the stack and some variables
      ed.bottomTab = "debug";
      if (ed.bottom.getBoundingClientRect().height < 240) ed.bottom.style.height = "240px";
      if (p.line > 0) this.show(p.file, p.line, p.pou);
    }
    this.apply();
    // a timeout being typed is not drawn over (the panel follows when the field is left)
    if (this.timeoutBox && ed.shadow.activeElement === this.timeoutBox) this.later = true;
    else ed.drawBottom();
  }

  serverItems(file) {
    return (this.state.breakpoints || []).filter((b) => b.file === file).map((b) => ({
      line: b.requested, condition: b.condition, hit_count: b.hit_count, log: b.log,
    }));
  }

  // the breakpoints of a file as the gutter shows them
  shownOf(file) {
    const mine = this.local.get(file);
    if (mine) return mine.items.map((i) => ({ ...i, requested: i.line, shown: i.line, verified: true, pending: true }));
    return (this.state.breakpoints || []).filter((b) => b.file === file)
      .map((b) => ({ ...b, shown: b.verified && b.line ? b.line : b.requested }));
  }

  // the arrow and the lit lines of the file in view
  places() {
    const found = [];
    const m = this.state;
    const current = this.editor.current;
    if (m.paused && m.paused.file === current && m.paused.line > 0) found.push([m.paused.line, "paused"]);
    const frame = (m.frames || [])[m.frame || 0];
    if (frame && frame.index > 0 && frame.file === current && frame.line > 0) found.push([frame.line, "frame"]);
    return found;
  }

  marker(line) {
    const current = this.editor.current;
    if (!current) return null;
    const bp = this.shownOf(current).find((b) => b.shown === line) || null;
    const place = this.places().find(([l]) => l === line);
    const arrow = place ? (place[1] === "paused" ? "top" : "frame") : null;
    return bp || arrow ? new DebugMarker(bp, arrow) : null;
  }

  apply() {
    const view = this.editor.view;
    if (!view || !this.editor.current) return;
    view.dispatch({ effects: [setLit.of(litDecorations(view.state.doc, this.places())), debugChanged.of(null)] });
  }

  // ---- breakpoints
  refusal() {
    const m = this.state;
    if (!m.on) return m.why || "Not online with a resource that runs this project.";
    if (!m.allowed) return `Debugging: ${m.reason}.`;
    return "";
  }

  itemsOf(file) {
    const mine = this.local.get(file);
    return mine ? mine.items.map((i) => ({ ...i })) : this.serverItems(file);
  }

  toggle(line) {
    const file = this.editor.current;
    const why = this.refusal();
    if (why) {
      this.editor.flash(why);
      return;
    }
    const items = this.itemsOf(file);
    const at = this.shownOf(file).find((b) => b.shown === line || b.requested === line);
    const kept = at ? items.filter((i) => i.line !== at.requested) : [...items, { line }];
    this.put(file, kept);
  }

  put(file, items) {
    const clean = items.map((i) => {
      const out = { line: i.line };
      if (i.condition) out.condition = i.condition;
      if (i.hit_count) out.hit_count = i.hit_count;
      if (i.log && i.log.length) out.log = i.log;
      return out;
    });
    this.local.set(file, { items: clean, at: Date.now() });
    this.editor.send({ k: "breakpoints", file, items: clean });
    this.apply();
    this.editor.drawBottom();
  }

  // a small form in the note above the text: condition, hit count, logged expressions
  edit(line) {
    const ed = this.editor;
    const file = ed.current;
    const why = this.refusal();
    if (why) {
      ed.flash(why);
      return;
    }
    const at = this.shownOf(file).find((b) => b.shown === line || b.requested === line);
    const asked = at ? at.requested : line;
    const box = (name, value, width, hint) => el("input", {
      "data-bp-field": name, value: value == null ? "" : String(value), placeholder: hint,
      style: `font:13px ui-monospace,monospace;padding:2px 6px;width:${width}`,
    });
    const condition = box("condition", at && at.condition, "220px", "ST condition, e.g. level > 700");
    const hits = box("hit_count", at && at.hit_count, "70px", "hit no.");
    const logged = box("log", at && at.log ? at.log.join(", ") : "", "220px", "a logpoint: x, y");
    const done = () => {
      ed.drawNote();
      setTimeout(() => ed.view.focus(), 0);
    };
    const apply = () => {
      const count = hits.value.trim();
      if (count && !/^[1-9][0-9]{0,8}$/.test(count)) {
        ed.flash("A hit count is a whole number from 1.");
        return;
      }
      const item = { line: asked, condition: condition.value.trim(), hit_count: count ? Number(count) : null, log: splitExpressions(logged.value) };
      this.put(file, [...this.itemsOf(file).filter((i) => i.line !== asked), item]);
      done();
    };
    const remove = () => {
      this.put(file, this.itemsOf(file).filter((i) => i.line !== asked));
      done();
    };
    const buttons = [
      el("button", { style: BUTTON, "data-bp-action": "apply", onclick: apply }, "Apply"),
      el("button", { style: BUTTON, "data-bp-action": "remove", onclick: remove }, "Remove"),
      el("button", { style: BUTTON, "data-bp-action": "cancel", onclick: done }, "Cancel"),
    ];
    const row = el("div", { "data-testid": "breakpoint-form", style: "display:flex;flex-wrap:wrap;gap:4px 8px;align-items:center" },
      el("b", {}, `Breakpoint at line ${asked}`), "Condition", condition, "Hit count", hits, "Log", logged, ...buttons);
    for (const input of [condition, hits, logged]) {
      input.addEventListener("keydown", (e) => {
        if (e.key !== "Enter" && e.key !== "Escape") return;
        e.preventDefault();
        e.stopPropagation();
        if (e.key === "Enter") apply();
        else done();
      });
    }
    ed.note.replaceChildren(row);
    ed.note.style.display = "block";
    condition.focus();
  }

  // ---- the panel's controls
  blocked(name) {
    const why = this.refusal();
    if (why) return why;
    if (!this.state.paused) return "No program is in BKPT.";
    if (name === "run_to" && !this.editor.current) return "Open the file to run to.";
    return "";
  }

  act(name) {
    const ed = this.editor;
    const why = this.blocked(name);
    if (why) {
      ed.flash(why);
      return;
    }
    if (name === "run_to") {
      const s = ed.view.state;
      ed.send({ k: "debug", action: "run_to", file: ed.current, line: s.doc.lineAt(s.selection.main.head).number });
    } else {
      ed.send({ k: "debug", action: name });
    }
  }

  // F5, F10, F11, Shift+F11 while a program is in BKPT (not while typing in a field)
  key(e) {
    if (!this.state.paused || e.ctrlKey || e.altKey || e.metaKey) return;
    const target = e.composedPath()[0];
    if (target && (target.tagName === "INPUT" || target.tagName === "TEXTAREA")) return;
    const name = e.key === "F5" ? "continue" : e.key === "F10" ? "over" : e.key === "F11" ? (e.shiftKey ? "out" : "into") : null;
    if (!name) return;
    e.preventDefault();
    e.stopPropagation();
    this.act(name);
  }

  tabLabel() {
    return this.state.paused ? "Debug (BKPT)" : "Debug";
  }

  draw() {
    const m = this.state;
    const root = el("div", { "data-testid": "debug-panel", style: "display:flex;flex-direction:column;font:12.5px system-ui,sans-serif;min-height:100%" });
    const where = el("div", { "data-testid": "debug-where", style: "padding:4px 8px;font-weight:600" }, this.whereText());
    const buttons = ACTIONS.map(([name, label, key]) => {
      const why = this.blocked(name);
      const b = el("button", {
        style: BUTTON, "data-debug": name, title: why || (key ? `${label} (${key})` : label),
        onclick: () => this.act(name),
      }, label);
      b.disabled = !!why;
      return b;
    });
    const why = this.blocked("continue");
    const reason = el("span", { "data-testid": "debug-reason", style: "color:#868e96" }, why);
    const bar = el("div", { style: "display:flex;flex-wrap:wrap;gap:4px 6px;align-items:center;padding:2px 8px 4px" }, ...buttons, reason, this.timeoutControl());
    const left = el("div", { style: "flex:2;min-width:180px;overflow:auto;border-right:1px solid #dee2e6" }, this.stackTable(), this.breakpointTable());
    const right = el("div", { style: "flex:3;min-width:200px;overflow:auto" }, this.variableTable());
    const columns = el("div", { style: "display:flex;flex:1;min-height:0;border-top:1px solid #dee2e6" }, left, right);
    root.append(where, bar, columns);
    // drawn anew at each change (a logpoint's hits): the lists stay where they were scrolled
    const [top, down] = [this.left ? this.left.scrollTop : 0, this.right ? this.right.scrollTop : 0];
    [this.left, this.right] = [left, right];
    queueMicrotask(() => {
      left.scrollTop = top;
      right.scrollTop = down;
    });
    return root;
  }

  // how long a program stays in BKPT once no debugger speaks to the resource (a page gone)
  timeoutControl() {
    const m = this.state;
    if (!m.on || !m.timeout_s) return "";
    const box = el("input", {
      type: "number", min: "5", max: "3600", value: String(m.timeout_s), "data-testid": "debug-timeout",
      style: "width:64px;font:12.5px system-ui,sans-serif;padding:1px 4px",
      title: "If this page goes, the resource lets the program continue and clears the breakpoints after this many seconds",
    });
    const set = () => {
      const seconds = Number(box.value);
      if (!Number.isInteger(seconds) || seconds < 5 || seconds > 3600) return this.editor.flash("A debug timeout is 5 to 3600 s.");
      if (this.refusal()) return this.editor.flash(this.refusal());
      this.editor.send({ k: "debug", action: "timeout", seconds });
    };
    box.addEventListener("keydown", (e) => {
      if (e.key === "Enter") set();
    });
    box.addEventListener("change", set);
    box.addEventListener("blur", () => {
      if (this.later) {
        this.later = false;
        setTimeout(() => this.editor.drawBottom(), 0);
      }
    });
    box.disabled = !m.allowed;
    this.timeoutBox = box;
    return el("span", { style: "margin-left:auto;color:#495057;white-space:nowrap" }, "Continues by itself after ", box, " s without a debugger");
  }

  whereText() {
    const m = this.state;
    if (!m.on) return m.why || "Not online.";
    if (m.error) return `${m.resource}: the debug state was ${m.error}`;
    const p = m.paused;
    if (!p) {
      const others = (m.in_bkpt || []).length ? ` (${m.in_bkpt.join(", ")} in BKPT)` : "";
      return `${m.resource}: no program in BKPT${others}. Click in the gutter left of a line number for a breakpoint; right-click it for a condition, a hit count or a logpoint.`;
    }
    const at = p.line > 0 ? `${p.file}:${p.line} (${p.pou})` : `the end of its program cycle (${p.pou})`;
    return `${p.program} in BKPT at ${at}, ${p.reason}`;
  }

  stackTable() {
    const m = this.state;
    const table = el("table", { "data-testid": "debug-stack", style: "border-collapse:collapse;width:100%" });
    table.append(el("tr", {}, el("th", { colspan: "2", style: `${CELL};text-align:left;color:#495057` }, "Call stack")));
    for (const f of m.frames || []) {
      const on = f.index === (m.frame || 0);
      table.append(el("tr", {
        "data-frame": String(f.index), style: `cursor:pointer;border-bottom:1px solid #f1f3f5;${on ? "background:#e7f5ff;font-weight:600" : ""}`,
        title: f.instance ? `instance ${f.instance}` : f.kind,
        onclick: () => this.chooseFrame(f),
      }, el("td", { style: CELL }, `${f.name}`), el("td", { style: `${CELL};color:#1864ab;width:100%` }, f.line ? `${f.file}:${f.line}` : f.file)));
    }
    if (!(m.frames || []).length) table.append(el("tr", {}, el("td", { colspan: "2", style: `${CELL};color:#868e96;white-space:normal` }, "At a break: the program, the blocks, methods and functions it is in.")));
    return table;
  }

  chooseFrame(f) {
    this.editor.send({ k: "debug", action: "frame", frame: f.index });
    if (f.file && f.line > 0) this.show(f.file, f.line, f.pou);
  }

  // a place in the editor; the standard library's blocks (TON, ...) are compiled with the
  // project but are no file of it (the compiler names them "stdlib/...")
  show(file, line, pou) {
    if (file.startsWith("stdlib/")) this.editor.flash(`${pou} is of the standard library (${file}:${line}): not a file of the project.`);
    else this.editor.select(file, line);
  }

  breakpointTable() {
    const table = el("table", { "data-testid": "debug-breakpoints", style: "border-collapse:collapse;width:100%;margin-top:6px" });
    table.append(el("tr", {}, el("th", { colspan: "3", style: `${CELL};text-align:left;color:#495057` }, "Breakpoints")));
    for (const b of this.state.breakpoints || []) {
      const line = b.verified && b.line ? b.line : b.requested;
      const what = [b.log ? `log ${b.log.join(", ")}` : "", b.condition ? `when ${b.condition}` : "", b.hit_count ? `from hit ${b.hit_count}` : ""].filter(Boolean).join(" ");
      const detail = b.verified ? `${what}${what ? " · " : ""}${b.hits} hit${b.hits === 1 ? "" : "s"}` : b.message;
      const remove = el("span", { style: "color:#868e96;cursor:pointer", title: "Remove", "data-remove": `${b.file}:${line}` }, "×");
      remove.addEventListener("click", (e) => {
        e.stopPropagation();
        if (this.refusal()) return this.editor.flash(this.refusal());
        this.put(b.file, this.itemsOf(b.file).filter((i) => i.line !== b.requested));
      });
      table.append(el("tr", {
        "data-breakpoint": `${b.file}:${line}`, style: "cursor:pointer;border-bottom:1px solid #f1f3f5",
        onclick: () => this.editor.select(b.file, line),
      }, el("td", { style: `${CELL};color:${b.verified ? "#c92a2a" : "#868e96"}` }, `${b.file}:${line}`),
      el("td", { style: `${CELL};width:100%;color:#495057;white-space:normal` }, detail), el("td", { style: CELL }, remove)));
    }
    return table;
  }

  variableTable() {
    const m = this.state;
    const table = el("table", { "data-testid": "debug-variables", style: "border-collapse:collapse;width:100%;font-family:ui-monospace,monospace" });
    table.append(el("tr", {}, ...["Variable", "Value", "Type"].map((h) => el("th", { style: `${CELL};text-align:left;color:#495057;font-family:system-ui,sans-serif` }, h))));
    for (const v of m.variables || []) {
      const toggle = v.children ? (v.open ? "▾ " : "▸ ") : "";
      const name = el("td", { style: `${CELL};padding-left:${8 + 14 * v.depth}px` }, `${toggle}${v.name}`);
      const title = v.resource_path
        ? `${v.resource_path}: written or forced in Online test as at any time`
        : "a local of a function or method: shown, not written";
      const row = el("tr", { "data-var-path": v.path, title, style: "border-bottom:1px solid #f1f3f5" }, name,
        el("td", { style: `${CELL};width:100%;color:#1864ab`, "data-value": v.path }, v.value),
        el("td", { style: `${CELL};color:#868e96` }, v.type));
      if (v.children) {
        row.style.cursor = "pointer";
        row.addEventListener("click", () => this.editor.send({ k: "debug", action: v.open ? "collapse" : "expand", path: v.path }));
      }
      table.append(row);
    }
    if (!(m.variables || []).length) table.append(el("tr", {}, el("td", { colspan: "3", style: `${CELL};color:#868e96;font-family:system-ui,sans-serif;white-space:normal` }, "At a break: the variables of the chosen frame (click a block, a structure or an array to open it).")));
    return table;
  }
}
