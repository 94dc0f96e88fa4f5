// The PADT's code editor in the browser: CodeMirror 6 laid over the centre of viser's page
// (the area of its 3D canvas), with a toolbar above and a panel of problems, references,
// live values and events below. It speaks to the server (frontend/editor/) in two directions:
//  - to the server: messages queued with a sequence number and written, all the unanswered
//    ones at once, into a hidden viser text input ("Editor message"); viser sends an input's
//    value at most every 50 ms and drops the values in between, so a message stays in the
//    queue until the server acknowledges its number;
//  - from the server: `window.padtEditor.receive(message)` run by viser's RunJavascript.
// Edits go as changes (never the whole text per keystroke) with a version per document; the
// server answers diagnostics for the newest version only.
import { EditorState, EditorSelection, Compartment, StateEffect, StateField, RangeSetBuilder } from "@codemirror/state";
import {
  EditorView, keymap, lineNumbers, highlightActiveLine, highlightActiveLineGutter,
  drawSelection, highlightSpecialChars, hoverTooltip, Decoration, WidgetType,
} from "@codemirror/view";
import { defaultKeymap, history, historyKeymap, indentWithTab } from "@codemirror/commands";
import {
  bracketMatching, foldGutter, foldKeymap, indentOnInput, syntaxHighlighting, HighlightStyle,
} from "@codemirror/language";
import { searchKeymap, highlightSelectionMatches, search } from "@codemirror/search";
import { autocompletion, completionKeymap, closeBrackets, closeBracketsKeymap, startCompletion, snippet } from "@codemirror/autocomplete";
import { setDiagnostics, lintGutter } from "@codemirror/lint";
import { tags } from "@lezer/highlight";
import { structuredText, stFolding } from "./st_language.js";
import { el, BUTTON, TAB } from "./dom.js";
import { debugGutter, litField, DebugPanel } from "./debugging.js";

const INPUT_LABEL = "Editor message";
const DEBOUNCE_MS = 150;
const ANSWER_TIMEOUT_MS = 5000;
const RESEND_MS = 500; // an unacknowledged queue is written again after this
const Z_INDEX = 90; // above the canvas, below viser's modals (100: a confirmation must not be under the editor), menus and notifications

const highlight = HighlightStyle.define([
  { tag: tags.keyword, color: "#7048e8", fontWeight: "600" },
  { tag: tags.typeName, color: "#0b7285" },
  { tag: tags.comment, color: "#868e96", fontStyle: "italic" },
  { tag: tags.string, color: "#2b8a3e" },
  { tag: tags.number, color: "#d9480f" },
  { tag: tags.meta, color: "#a61e4d" },
  { tag: tags.function(tags.variableName), color: "#1864ab" },
  { tag: tags.operator, color: "#495057" },
]);

const theme = EditorView.theme({
  "&": { height: "100%", fontSize: "13.5px", backgroundColor: "#ffffff" },
  ".cm-scroller": { fontFamily: "ui-monospace, 'DejaVu Sans Mono', Menlo, Consolas, monospace", lineHeight: "1.5" },
  ".cm-gutters": { backgroundColor: "#f8f9fa", borderRight: "1px solid #dee2e6", color: "#868e96" },
  ".cm-activeLine": { backgroundColor: "#f1f3f5" },
  ".cm-activeLineGutter": { backgroundColor: "#e9ecef" },
  ".padt-live": {
    marginLeft: "3ch", padding: "0 5px", borderRadius: "3px", background: "#e7f5ff",
    color: "#1864ab", fontSize: "12px",
  },
  ".padt-live-stale": { color: "#868e96", background: "#f1f3f5" },
  ".padt-live-forced": { color: "#c92a2a", background: "#fff5f5" },
  ".cm-tooltip-hover": { maxWidth: "640px", padding: "4px 8px", whiteSpace: "pre-wrap" },
  ".padt-debug-gutter": { cursor: "pointer" },
  ".padt-debug-gutter .cm-gutterElement": { display: "flex", alignItems: "center", gap: "2px", padding: "0 2px" },
  ".padt-bp": { flex: "none", width: "10px", height: "10px", borderRadius: "50%", background: "#e03131", boxSizing: "border-box" },
  ".padt-bp-log": { borderRadius: "2px", transform: "rotate(45deg) scale(0.85)" },
  ".padt-bp-cond": { boxShadow: "inset 0 0 0 2px #ffd8a8" },
  ".padt-bp-unverified": { background: "transparent", border: "2px solid #adb5bd", boxShadow: "none" },
  ".padt-bp-pending": { opacity: "0.5" },
  ".padt-bp-none": { flex: "none", width: "10px" },
  // the arrow where the program stands: a triangle drawn by its borders (no font needed)
  ".padt-arrow": { flex: "none", width: "0", height: "0", borderTop: "6px solid transparent", borderBottom: "6px solid transparent", borderLeft: "9px solid #e8590c" },
  ".padt-arrow-frame": { borderLeftColor: "#1971c2" },
  ".padt-paused-line": { backgroundColor: "#ffec99 !important" },
  // the lines the unit tests ran (green), never ran (red), ran without taking every way (amber)
  ".padt-cov-covered": { backgroundColor: "#ebfbee" },
  ".padt-cov-uncovered": { backgroundColor: "#ffe3e3" },
  ".padt-cov-partial": { backgroundColor: "#fff3bf" },
  ".padt-frame-line": { backgroundColor: "#d0ebff !important" },
});

// ---- the live values at the end of lines

// viser's canvas sits in a box of its own (the one it watches to know whether the canvas is
// in view) inside the area that the docked panels leave free: the editor is laid over the
// area and hides the box.
function canvasPlace() {
  const canvas = document.querySelector("canvas[data-engine]") || document.querySelector("canvas");
  const canvasBox = canvas && canvas.parentElement && canvas.parentElement.parentElement
    && canvas.parentElement.parentElement.parentElement;
  return { canvasBox, area: canvasBox && canvasBox.parentElement };
}

class LiveWidget extends WidgetType {
  constructor(text, quality) {
    super();
    this.text = text;
    this.quality = quality;
  }
  eq(other) {
    return other.text === this.text && other.quality === this.quality;
  }
  toDOM() {
    const span = document.createElement("span");
    this.updateDOM(span);
    return span;
  }
  // a new value changes the text in place: the line is not drawn anew, so a hover over it
  // (which keeps the element under the mouse) survives the values' updates
  updateDOM(span) {
    span.className = `padt-live padt-live-${this.quality === "forced" ? "forced" : this.quality === "live" ? "live" : "stale"}`;
    span.dataset.quality = this.quality;
    span.textContent = this.text;
    return true;
  }
  ignoreEvent() {
    return true;
  }
}

const setLive = StateEffect.define();
const liveField = StateField.define({
  create: () => Decoration.none,
  update(value, tr) {
    value = value.map(tr.changes);
    for (const e of tr.effects) if (e.is(setLive)) value = e.value;
    return value;
  },
  provide: (f) => EditorView.decorations.from(f),
});

function liveDecorations(doc, items) {
  const builder = new RangeSetBuilder();
  for (const item of [...items].sort((a, b) => a.line - b.line)) {
    if (item.line < 1 || item.line > doc.lines) continue;
    const end = doc.line(item.line).to;
    builder.add(end, end, Decoration.widget({ widget: new LiveWidget(item.text, item.quality), side: 1 }));
  }
  return builder.finish();
}

// ---- coverage: each line with a statement shaded by how the unit tests ran it

const setCoverage = StateEffect.define();
const coverageField = StateField.define({
  create: () => Decoration.none,
  update(value, tr) {
    value = value.map(tr.changes);
    for (const e of tr.effects) if (e.is(setCoverage)) value = e.value;
    return value;
  },
  provide: (f) => EditorView.decorations.from(f),
});

// `shown`: the file's {lines: {line: hits}, branches: [{line, label, taken}]}; a title says
// in words what the shade says, for who does not tell the colours apart
function coverageDecorations(doc, shown) {
  const builder = new RangeSetBuilder();
  if (!shown) return builder.finish();
  const missed = new Map();
  for (const b of shown.branches || []) {
    if (!b.taken) missed.set(b.line, [...(missed.get(b.line) || []), b.label]);
  }
  const lines = Object.entries(shown.lines || {}).map(([line, hits]) => [Number(line), hits]);
  for (const [number, hits] of lines.sort((a, b) => a[0] - b[0])) {
    if (number < 1 || number > doc.lines) continue;
    const notTaken = missed.get(number);
    const how = hits === 0 ? "uncovered" : notTaken ? "partial" : "covered";
    let title = hits === 0 ? "never ran in the tests" : `ran ${hits} time${hits === 1 ? "" : "s"} in the tests`;
    if (hits && notTaken) title += `; not taken: ${notTaken.join(", ")}`;
    const at = doc.line(number).from;
    builder.add(at, at, Decoration.line({ class: `padt-cov-${how}`, attributes: { "data-coverage": how, title } }));
  }
  return builder.finish();
}

// ---- the page around the editor

class PadtEditor {
  constructor() {
    this.seq = 0;
    this.outbox = []; // [seq, message], until the server acknowledges seq
    this.writes = 0;
    this.resend = null;
    this.docs = new Map(); // file -> {file, label, state, version, base, pending, readonly, reason, diagnostics}
    this.current = null;
    this.waiting = new Map(); // request id -> resolve
    this.nextId = 1;
    this.back = []; // where go to definition came from: [file, pos]
    this.problems = [];
    this.references = [];
    this.bottomTab = "problems";
    this.liveItems = []; // the lines in view with their variables' values, when online
    this.events = []; // the selected resource's newest events, newest first
    this.coverage = {}; // file -> its lines' hits and branches, from the last run with coverage
    this.showDrawing = false;
    this.readonlyCompartment = new Compartment();
    this.debug = new DebugPanel(this);
    this.build();
  }

  // ---- to the server
  send(message) {
    this.seq += 1;
    this.outbox.push([this.seq, message]);
    this.flushOutbox();
  }

  flushOutbox() {
    const label = this.inputLabel();
    if (!label || !window.__padtWrite) {
      setTimeout(() => this.flushOutbox(), 200);
      return;
    }
    this.writes += 1; // the same queue written again is still a change of the input's value
    // past viser's throttle of the panel's inputs (frontend/page_writer.py)
    window.__padtWrite(label, JSON.stringify({ s: this.outbox, w: this.writes }));
    // a message sent while the websocket reconnects is lost: written again until the
    // server acknowledges it
    if (!this.resend) {
      this.resend = setTimeout(() => {
        this.resend = null;
        if (this.outbox.length) this.flushOutbox();
      }, RESEND_MS);
    }
  }

  inputLabel() {
    if (this.label && this.label.isConnected) return this.label; // found again when viser redraws
    this.label = Array.from(document.querySelectorAll("label")).find((x) => x.textContent === INPUT_LABEL);
    if (!this.label) return null;
    const row = this.label.parentElement.parentElement.parentElement;
    if (row.style.display !== "none") row.style.display = "none";
    return this.label;
  }

  ask(message) {
    const id = this.nextId++;
    return new Promise((resolve) => {
      this.waiting.set(id, resolve);
      this.send({ ...message, id });
      setTimeout(() => {
        if (this.waiting.delete(id)) resolve(null);
      }, ANSWER_TIMEOUT_MS);
    });
  }

  // ---- the page
  build() {
    // The editor lives in a shadow root: the page's observers of every change below
    // document.body (viser's, ours) then do not run at each keystroke.
    const host = el("div", {
      id: "padt-editor",
      style: `position:fixed;z-index:${Z_INDEX};display:none;background:#fff;border-left:1px solid #dee2e6;border-right:1px solid #dee2e6`,
    });
    this.shadow = host.attachShadow({ mode: "open" });
    const root = el("div", { style: "display:flex;flex-direction:column;height:100%;font:13px system-ui,sans-serif;color:#212529" });
    this.shadow.append(root);
    this.tabs = el("div", { "data-testid": "editor-tabs", style: "display:flex;overflow-x:auto;flex:1;min-width:0" });
    const button = (name, label, title) => {
      const b = el("button", { style: BUTTON, title, "data-action": name, onclick: () => this.action(name) }, label);
      return b;
    };
    this.buttons = {
      save: button("save", "Save", "Save the file (Ctrl+S)"),
      compile: button("compile", "Compile", "Compile the project twice and compare the CRCs"),
      download: button("download", "Download", "Load the project into a resource in STOP"),
      online_change: button("online_change", "Online change", "Change the running configuration"),
    };
    this.drawingToggle = el("button", { style: BUTTON, "data-action": "drawing", onclick: () => this.toggleDrawing() }, "Plant drawing");
    const toolbar = el(
      "div",
      { style: "display:flex;flex-wrap:wrap;align-items:center;gap:4px 6px;padding:4px 6px;background:#f8f9fa" },
      ...Object.values(this.buttons),
      el("span", { style: "flex:1" }),
      this.drawingToggle
    );
    const tabRow = el("div", { style: "display:flex;border-bottom:1px solid #dee2e6;background:#f8f9fa;min-height:28px" }, this.tabs);
    this.note = el("div", { "data-testid": "editor-note", style: "display:none;padding:4px 8px;background:#fff9db;border-bottom:1px solid #ffe066" });
    this.host = el("div", { "data-testid": "editor-host", style: "flex:1;min-height:60px;overflow:hidden;position:relative" });
    this.message = el("div", { "data-testid": "editor-message", style: "padding:24px;color:#495057" }, "Open a file of a project from the tree.");
    this.host.append(this.message);
    const splitter = el("div", { style: "height:5px;cursor:row-resize;background:#e9ecef;flex:none" });
    this.bottomTabs = el("div", { style: "display:flex;min-width:0" });
    this.status = el("div", { "data-testid": "editor-status", style: "flex:1;min-width:0;text-align:right;padding:4px 8px;color:#495057;overflow:hidden;text-overflow:ellipsis;white-space:nowrap" });
    const bottomBar = el("div", { style: "display:flex;align-items:center;border-bottom:1px solid #dee2e6;background:#f8f9fa" }, this.bottomTabs, this.status);
    this.bottomBody = el("div", { "data-testid": "editor-bottom", style: "overflow:auto;flex:1;font:12.5px ui-monospace,monospace" });
    this.bottom = el("div", { style: "height:170px;display:flex;flex-direction:column;flex:none" }, bottomBar, this.bottomBody);
    root.append(toolbar, tabRow, this.note, this.host, splitter, this.bottom);
    splitter.addEventListener("mousedown", (e) => this.resizeBottom(e));
    // Ctrl+S anywhere in the editor's area (a button of the toolbar may have the focus)
    root.addEventListener("keydown", (e) => {
      if ((e.ctrlKey || e.metaKey) && e.key === "s") {
        e.preventDefault();
        this.save();
      }
    });
    document.addEventListener("keydown", (e) => this.debug.key(e), true);
    document.body.append(host);
    this.root = host;
    this.view = new EditorView({ state: this.newState("", true), parent: document.createElement("div"), root: this.shadow });
    this.view.dom.style.height = "100%";
    this.drawBottom();
    this.follow();
  }

  // Laid exactly over viser's canvas: its container keeps the space the docked panels leave.
  follow() {
    const place = () => {
      const area = canvasPlace().area;
      if (!area) return;
      const r = area.getBoundingClientRect();
      const s = this.root.style;
      s.left = `${r.left}px`;
      s.top = `${r.top}px`;
      s.width = `${r.width}px`;
      s.height = `${r.height}px`;
      if (!this.observed || this.observed !== area) {
        this.observed = area;
        if (this.observer) this.observer.disconnect();
        this.observer = new ResizeObserver(place);
        this.observer.observe(area);
      }
    };
    place();
    window.addEventListener("resize", place);
    setInterval(() => this.show(this.visible), 1000); // a canvas drawn anew is hidden too
    // the canvas is drawn late and anew when the page's layout changes
    new MutationObserver(() => {
      if (!this.observed || !document.body.contains(this.observed)) place();
    }).observe(document.body, { childList: true, subtree: true });
    setInterval(place, 1000);
  }

  show(on) {
    const editing = on && !this.showDrawing;
    this.root.style.display = editing ? "block" : "none";
    this.visible = on;
    // the canvas under the editor is out of the page while the editor covers it: viser
    // then stops drawing it (it draws only a canvas in view). It draws its scene anew for a
    // quarter of a second after every message that is not for its panels, so the editor's
    // live values (ten a second) had it drawn without pause; in a browser that draws
    // without a GPU that took more than a core
    const { canvasBox } = canvasPlace();
    if (canvasBox) canvasBox.style.display = editing ? "none" : "";
  }

  toggleDrawing() {
    this.showDrawing = !this.showDrawing;
    this.show(this.visible);
    this.drawingButton().textContent = this.showDrawing ? "Editor" : "Plant drawing";
  }

  drawingButton() {
    // while the drawing shows, the editor is hidden: a small button stays to bring it back
    if (!this.backButton) {
      this.backButton = el("button", {
        style: `${BUTTON}position:fixed;z-index:${Z_INDEX};display:none`, "data-action": "editor",
        onclick: () => this.toggleDrawing(),
      }, "Editor");
      document.body.append(this.backButton);
    }
    const b = this.backButton;
    b.style.display = this.showDrawing && this.visible ? "block" : "none";
    b.style.left = `${parseFloat(this.root.style.left) + 8}px`;
    b.style.top = `${parseFloat(this.root.style.top) + 8}px`;
    return this.drawingToggle;
  }

  resizeBottom(e) {
    e.preventDefault();
    const start = e.clientY;
    const height = this.bottom.getBoundingClientRect().height;
    const move = (m) => {
      const total = this.root.getBoundingClientRect().height;
      this.bottom.style.height = `${Math.max(60, Math.min(total - 140, height + start - m.clientY))}px`;
    };
    const up = () => {
      document.removeEventListener("mousemove", move);
      document.removeEventListener("mouseup", up);
    };
    document.addEventListener("mousemove", move);
    document.addEventListener("mouseup", up);
  }

  action(name) {
    if (name === "save") this.save();
    else this.send({ k: "button", name });
  }

  // ---- documents
  newState(text, readonly) {
    const editor = this;
    return EditorState.create({
      doc: text,
      extensions: [
        debugGutter(editor),
        litField,
        lineNumbers(),
        highlightActiveLineGutter(),
        highlightSpecialChars(),
        history(),
        foldGutter(),
        stFolding,
        drawSelection(),
        indentOnInput(),
        syntaxHighlighting(highlight),
        bracketMatching(),
        closeBrackets(),
        highlightActiveLine(),
        highlightSelectionMatches(),
        search({ top: true }),
        lintGutter(),
        structuredText,
        autocompletion({ override: [(ctx) => editor.complete(ctx)], activateOnTyping: true }),
        hoverTooltip((view, pos) => editor.hover(view, pos), { hoverTime: 350 }),
        liveField,
        coverageField,
        this.readonlyCompartment.of([EditorState.readOnly.of(readonly), EditorView.editable.of(!readonly)]),
        keymap.of([
          { key: "F12", run: (v) => (editor.definition(v.state.selection.main.head), true) },
          { key: "Shift-F12", run: (v) => (editor.findReferences(v.state.selection.main.head), true) },
          { key: "Alt-ArrowLeft", run: () => (editor.goBack(), true) },
          { key: "F2", run: (v) => (editor.rename(v.state.selection.main.head), true) },
          { key: "Ctrl-Space", run: startCompletion },
          ...closeBracketsKeymap, ...defaultKeymap, ...searchKeymap, ...historyKeymap,
          ...foldKeymap, ...completionKeymap, indentWithTab,
        ]),
        EditorView.updateListener.of((u) => editor.updated(u)),
        EditorView.domEventHandlers({
          mousedown: (e, view) => {
            if (!(e.ctrlKey || e.metaKey) || e.button !== 0) return false;
            const pos = view.posAtCoords({ x: e.clientX, y: e.clientY });
            if (pos == null) return false;
            e.preventDefault();
            editor.definition(pos);
            return true;
          },
        }),
        theme,
      ],
    });
  }

  updated(update) {
    const doc = this.current && this.docs.get(this.current);
    if (!doc) return;
    if (update.docChanged) {
      doc.pending = doc.pending ? doc.pending.compose(update.changes) : update.changes;
      clearTimeout(doc.timer);
      doc.timer = setTimeout(() => this.flushChanges(doc), DEBOUNCE_MS);
      this.markDirty(doc, true);
    }
    if (update.viewportChanged || update.docChanged) {
      clearTimeout(this.viewTimer);
      this.viewTimer = setTimeout(() => this.sendView(), 250);
    }
  }

  flushChanges(doc) {
    if (!doc.pending) return;
    const changes = [];
    const base = doc.base;
    doc.pending.iterChanges((fromA, toA, _fromB, _toB, inserted) => {
      const a = base.lineAt(fromA);
      const b = base.lineAt(toA);
      changes.push([a.number, fromA - a.from, b.number, toA - b.from, inserted.toString()]);
    });
    doc.pending = null;
    doc.version += 1;
    doc.base = this.stateOf(doc).doc;
    this.send({ k: "change", file: doc.file, version: doc.version, changes });
  }

  stateOf(doc) {
    return doc.file === this.current ? this.view.state : doc.state;
  }

  flushAll() {
    for (const doc of this.docs.values()) {
      clearTimeout(doc.timer);
      this.flushChanges(doc);
    }
  }

  // `keyboard`: the editor takes the keyboard; not for a file the workspace reopens by
  // itself, while the user may be typing elsewhere (a password)
  select(file, line, col, keyboard = true) {
    const doc = this.docs.get(file);
    if (!doc) {
      this.afterOpen = { file, line, col };
      this.send({ k: "open", file });
      return;
    }
    if (this.current !== file) {
      const old = this.docs.get(this.current);
      if (old) old.state = this.view.state;
      this.current = file;
      this.view.setState(doc.state);
      this.applyDiagnostics(doc);
      this.applyCoverage();
      this.debug.apply();
      this.sendView();
    }
    if (!this.view.dom.parentElement || this.view.dom.parentElement !== this.host) {
      this.message.remove();
      this.host.append(this.view.dom);
    }
    this.drawTabs();
    this.drawNote();
    if (line) {
      const l = this.view.state.doc.line(Math.max(1, Math.min(line, this.view.state.doc.lines)));
      const pos = Math.min(l.to, l.from + Math.max(0, (col || 1) - 1));
      this.view.dispatch({ selection: EditorSelection.cursor(pos), scrollIntoView: true });
      this.view.dispatch({ effects: EditorView.scrollIntoView(pos, { y: "center" }) });
    }
    if (keyboard) this.view.focus();
  }

  markDirty(doc, dirty) {
    if (doc.dirty === dirty) return;
    doc.dirty = dirty;
    this.drawTabs();
  }

  drawTabs() {
    this.tabs.replaceChildren(
      ...[...this.docs.values()].map((doc) => {
        const on = doc.file === this.current;
        const tab = el("button", {
          style: TAB + (on ? "border-bottom-color:#228be6;font-weight:600;" : "color:#495057;"),
          "data-file": doc.file, title: doc.file,
          onclick: () => this.select(doc.file),
        }, (doc.dirty ? "● " : "") + doc.label);
        const close = el("span", {
          style: "margin-left:6px;color:#868e96", title: "Close",
          onclick: (e) => { e.stopPropagation(); this.close(doc.file); },
        }, "×");
        tab.append(close);
        return tab;
      })
    );
    const doc = this.docs.get(this.current);
    this.buttons.save.disabled = !doc || doc.readonly;
    this.buttons.save.title = doc && doc.readonly ? doc.reason : "Save the file (Ctrl+S)";
  }

  close(file) {
    const doc = this.docs.get(file);
    if (!doc) return;
    this.flushChanges(doc);
    this.docs.delete(file);
    this.send({ k: "close", file });
    if (this.current === file) {
      this.current = null;
      const next = [...this.docs.keys()][0];
      if (next) this.select(next);
      else {
        this.view.dom.remove();
        this.host.append(this.message);
      }
    }
    this.drawTabs();
  }

  drawNote() {
    const doc = this.docs.get(this.current);
    const note = this.note;
    note.replaceChildren();
    if (!doc) {
      note.style.display = "none";
      return;
    }
    if (doc.disk) {
      note.append(
        `${doc.file} was changed on disk since you opened it. `,
        el("button", { style: BUTTON, "data-action": "reload", onclick: () => this.resolveDisk(doc, "reload") }, "Reload from disk"),
        " ",
        el("button", { style: BUTTON, "data-action": "keep", onclick: () => this.resolveDisk(doc, "keep") }, "Keep mine")
      );
    } else if (doc.readonly) {
      note.append(doc.reason);
    } else {
      note.style.display = "none";
      return;
    }
    note.style.display = "block";
  }

  resolveDisk(doc, choice) {
    this.flushChanges(doc);
    this.send({ k: "disk", file: doc.file, choice });
    this.view.focus();
  }

  save() {
    const doc = this.docs.get(this.current);
    if (!doc || doc.readonly) return;
    this.flushChanges(doc);
    this.send({ k: "save", file: doc.file, version: doc.version });
  }

  sendView() {
    const doc = this.docs.get(this.current);
    if (!doc) return;
    const { from, to } = this.view.viewport;
    const d = this.view.state.doc;
    const view = { k: "view", file: doc.file, first: d.lineAt(from).number, last: d.lineAt(to).number };
    const key = JSON.stringify(view);
    if (key === this.viewSent) return; // typing on a line moves nothing into view
    this.viewSent = key;
    this.send(view);
  }

  // ---- the language services
  where(pos) {
    const line = this.view.state.doc.lineAt(pos);
    return { line: line.number, col: pos - line.from + 1 };
  }

  async complete(ctx) {
    const doc = this.docs.get(this.current);
    if (!doc) return null;
    const word = ctx.matchBefore(/[A-Za-z_0-9]*/);
    if (!ctx.explicit && (!word || word.from === word.to) && ctx.state.sliceDoc(ctx.pos - 1, ctx.pos) !== ".") return null;
    this.flushChanges(doc);
    const answer = await this.ask({ k: "complete", file: doc.file, version: doc.version, ...this.where(ctx.pos) });
    if (!answer || ctx.aborted) return null;
    return {
      from: word ? word.from : ctx.pos,
      options: answer.items.map((i, n) => ({
        label: i.label, type: i.kind, detail: i.detail, info: i.info || undefined,
        apply: i.snippet ? snippet(i.insert) : i.insert || i.label,
        boost: -n / answer.items.length, // the server's order: most relevant first
      })),
      validFor: /^[A-Za-z_0-9]*$/,
    };
  }

  async hover(view, pos) {
    const doc = this.docs.get(this.current);
    if (!doc) return null;
    this.flushChanges(doc);
    const answer = await this.ask({ k: "hover", file: doc.file, version: doc.version, ...this.where(pos) });
    if (!answer || !answer.signature) return null;
    return {
      pos,
      above: true,
      create: () => {
        const dom = el("div", { "data-testid": "editor-hover" },
          el("pre", { style: "margin:0;font:12.5px ui-monospace,monospace" }, answer.signature));
        if (answer.value) dom.append(el("div", { "data-testid": "hover-value", style: "color:#1864ab;margin-top:4px" }, `value now: ${answer.value}`));
        if (answer.comment) dom.append(el("div", { style: "margin-top:4px" }, answer.comment));
        if (answer.place) dom.append(el("div", { style: "color:#868e96;margin-top:4px" }, answer.place));
        return { dom };
      },
    };
  }

  async definition(pos) {
    const doc = this.docs.get(this.current);
    if (!doc) return;
    this.flushChanges(doc);
    const answer = await this.ask({ k: "definition", file: doc.file, version: doc.version, ...this.where(pos) });
    if (!answer || !answer.file) {
      this.flash(answer && answer.reason ? answer.reason : "No definition found here.");
      return;
    }
    this.back.push([doc.file, pos]);
    this.select(answer.file, answer.line, answer.col);
  }

  goBack() {
    const last = this.back.pop();
    if (!last) return;
    const [file, pos] = last;
    if (!this.docs.has(file)) return;
    this.select(file);
    this.view.dispatch({ selection: EditorSelection.cursor(Math.min(pos, this.view.state.doc.length)), scrollIntoView: true });
  }

  async findReferences(pos) {
    const doc = this.docs.get(this.current);
    if (!doc) return;
    this.flushChanges(doc);
    const answer = await this.ask({ k: "references", file: doc.file, version: doc.version, ...this.where(pos) });
    this.references = answer ? answer.items : [];
    this.referencesOf = answer ? answer.name : "";
    this.bottomTab = "references";
    this.drawBottom();
  }

  rename(pos) {
    const doc = this.docs.get(this.current);
    if (!doc || doc.readonly) return;
    const word = this.view.state.wordAt(pos);
    const old = word ? this.view.state.sliceDoc(word.from, word.to) : "";
    const box = el("input", { value: old, "data-testid": "rename-input", style: "font:13px ui-monospace,monospace;padding:2px 6px;width:220px" });
    const bar = el("div", { style: "display:flex;gap:6px;align-items:center" }, `Rename ${old} to `, box, " (Enter, Esc cancels)");
    this.note.replaceChildren(bar);
    this.note.style.display = "block";
    box.focus();
    box.select();
    box.addEventListener("keydown", (e) => {
      if (e.key !== "Escape" && e.key !== "Enter") return;
      // not passed on: the editor, focused again, would take the Enter as a line break
      e.preventDefault();
      e.stopPropagation();
      if (e.key === "Enter") {
        this.flushChanges(doc);
        this.send({ k: "rename", file: doc.file, version: doc.version, ...this.where(pos), name: box.value.trim() });
      }
      this.drawNote();
      setTimeout(() => this.view.focus(), 0);
    });
  }

  flash(text) {
    // beside the bottom panel's tabs, where it hides nothing the user must answer
    this.status.textContent = text;
    clearTimeout(this.flashTimer);
    this.flashTimer = setTimeout(() => { this.status.textContent = ""; }, 8000);
  }

  // ---- the bottom panel
  drawBottom() {
    const tabs = [
      ["problems", `Problems (${this.problems.length})`],
      ["references", this.referencesOf ? `References to ${this.referencesOf} (${this.references.length})` : "References"],
      ["live", "Live values"],
      ["events", "Events"],
      ["debug", this.debug.tabLabel()],
    ];
    this.bottomTabs.replaceChildren(
      ...tabs.map(([key, label]) =>
        el("button", {
          style: TAB + (key === this.bottomTab ? "border-bottom-color:#228be6;font-weight:600;" : "color:#495057;"),
          "data-bottom": key, onclick: () => { this.bottomTab = key; this.drawBottom(); },
        }, label)
      )
    );
    if (this.bottomTab === "debug") {
      this.bottomBody.replaceChildren(this.debug.draw());
      return;
    }
    if (this.bottomTab === "live" || this.bottomTab === "events") {
      this.bottomBody.replaceChildren(this.bottomTab === "live" ? this.liveTable() : this.eventTable());
      return;
    }
    const rows = this.bottomTab === "problems" ? this.problems : this.references;
    const table = el("table", { style: "border-collapse:collapse;width:100%", "data-testid": `${this.bottomTab}-list` });
    for (const r of rows) {
      const color = r.severity === "error" ? "#c92a2a" : r.severity === "warning" ? "#e67700" : "#495057";
      const tr = el("tr", {
        style: "cursor:pointer;border-bottom:1px solid #f1f3f5", "data-place": `${r.file}:${r.line}:${r.col}`,
        onclick: () => this.select(r.file, r.line, r.col),
      });
      if (this.bottomTab === "problems") tr.append(el("td", { style: `padding:2px 8px;color:${color};white-space:nowrap` }, r.code));
      tr.append(
        el("td", { style: "padding:2px 8px;white-space:nowrap;color:#1864ab" }, `${r.file}:${r.line}:${r.col}`),
        el("td", { style: "padding:2px 8px;width:100%" }, r.message || r.text || "")
      );
      table.append(tr);
    }
    if (!rows.length) {
      const empty = this.bottomTab === "problems" ? "No problems." : "Shift+F12 on a name lists where it is used.";
      table.append(el("tr", {}, el("td", { style: "padding:6px 8px;color:#868e96" }, empty)));
    }
    this.bottomBody.replaceChildren(table);
  }

  // each variable of the lines in view once, in the order of the lines, with its value
  liveTable() {
    const table = el("table", { style: "border-collapse:collapse;width:100%", "data-testid": "live-list" });
    const seen = new Set();
    for (const item of this.liveItems) {
      for (const [name, text, how] of item.values || []) {
        if (seen.has(name)) continue;
        seen.add(name);
        const color = how === "forced" ? "#c92a2a" : how === "live" ? "#212529" : "#868e96";
        table.append(el("tr", {
          style: "cursor:pointer;border-bottom:1px solid #f1f3f5", "data-live": name,
          onclick: () => this.select(this.current, item.line, 1),
        },
        el("td", { style: "padding:2px 8px;white-space:nowrap;font-family:monospace" }, name),
        el("td", { style: `padding:2px 8px;width:100%;font-family:monospace;color:${color}` }, text)));
      }
    }
    if (!seen.size) {
      const empty = "Online, when the file is what the selected resource runs: the values of the variables in the lines in view.";
      table.append(el("tr", {}, el("td", { style: "padding:6px 8px;color:#868e96" }, empty)));
    }
    return table;
  }

  eventTable() {
    const table = el("table", { style: "border-collapse:collapse;width:100%", "data-testid": "events-list" });
    const cell = "padding:2px 8px;white-space:nowrap";
    for (const e of this.events) {
      table.append(el("tr", { style: "border-bottom:1px solid #f1f3f5", "data-seq": String(e.seq), "data-kind": e.kind },
        el("td", { style: `${cell};color:#868e96;text-align:right` }, String(e.seq)),
        el("td", { style: `${cell};font-family:monospace` }, e.time),
        el("td", { style: `${cell};color:${e.color};font-weight:600` }, e.kind),
        el("td", { style: cell }, e.user),
        el("td", { style: "padding:2px 8px;width:100%" }, e.message)));
    }
    if (!this.events.length) {
      const empty = "The selected resource's newest events, once logged in to it (all of them: the Events screen).";
      table.append(el("tr", {}, el("td", { style: "padding:6px 8px;color:#868e96" }, empty)));
    }
    return table;
  }

  applyDiagnostics(doc) {
    if (doc.file !== this.current) return;
    const d = this.view.state.doc;
    const items = [];
    for (const x of doc.diagnostics) {
      if (x.line < 1 || x.line > d.lines) continue;
      const line = d.line(x.line);
      const from = Math.min(line.to, line.from + Math.max(0, x.col - 1));
      const word = this.view.state.wordAt(from);
      const to = word && word.from === from ? word.to : Math.min(line.to, from + 1);
      items.push({ from, to: Math.max(to, from), severity: x.severity === "error" ? "error" : x.severity === "warning" ? "warning" : "info", message: `${x.code}: ${x.message}`, source: x.code });
    }
    this.view.dispatch(setDiagnostics(this.view.state, items));
  }

  applyCoverage() {
    if (!this.current) return;
    const shades = coverageDecorations(this.view.state.doc, this.coverage[this.current]);
    this.view.dispatch({ effects: setCoverage.of(shades) });
  }

  // ---- from the server
  receive(m) {
    const handler = this["on_" + m.k];
    if (handler) handler.call(this, m);
  }

  on_ack(m) {
    this.outbox = this.outbox.filter(([seq]) => seq > m.seq);
  }

  on_show(m) {
    this.show(m.on);
    if (m.message !== undefined) this.message.textContent = m.message;
    for (const [name, b] of Object.entries(this.buttons)) {
      if (name === "save") continue;
      const why = m.disabled && m.disabled[name];
      b.disabled = !!why;
      if (why) b.title = why;
    }
  }

  on_open(m) {
    const old = this.docs.get(m.file);
    if (old && this.current === m.file) this.current = null;
    const doc = {
      file: m.file, label: m.label, version: m.version, readonly: m.readonly, reason: m.reason || "",
      state: this.newState(m.text, m.readonly), pending: null, diagnostics: [], dirty: false, disk: false,
    };
    doc.base = doc.state.doc;
    this.docs.set(m.file, doc);
    const after = this.afterOpen && this.afterOpen.file === m.file ? this.afterOpen : null;
    this.afterOpen = null;
    if (m.focus || after) {
      this.select(m.file, after && after.line, after && after.col, m.keyboard !== false);
    }
    else this.drawTabs();
  }

  on_goto(m) {
    if (this.docs.has(m.file)) this.select(m.file, m.line, m.col, m.keyboard !== false);
  }

  on_answer(m) {
    const resolve = this.waiting.get(m.id);
    if (resolve) {
      this.waiting.delete(m.id);
      resolve(m);
    }
  }

  on_diagnostics(m) {
    for (const [file, items] of Object.entries(m.files)) {
      const doc = this.docs.get(file);
      if (doc && doc.version === m.versions[file]) {
        doc.diagnostics = items;
        this.applyDiagnostics(doc);
      }
    }
    this.problems = m.problems;
    this.drawBottom();
  }

  on_saved(m) {
    const doc = this.docs.get(m.file);
    if (doc && doc.version === m.version) this.markDirty(doc, false);
  }

  on_disk(m) {
    const doc = this.docs.get(m.file);
    if (!doc) return;
    doc.disk = m.changed;
    if (this.current === m.file) this.drawNote();
  }

  on_replace(m) {
    // the server's text of a document replaces the browser's (reload from disk, a rename)
    const doc = this.docs.get(m.file);
    if (!doc) return;
    this.flushChanges(doc);
    const state = this.stateOf(doc);
    const spec = { changes: { from: 0, to: state.doc.length, insert: m.text } };
    if (doc.file === this.current) this.view.dispatch(spec);
    else doc.state = doc.state.update(spec).state;
    if (m.saved) {
      clearTimeout(doc.timer);
      this.flushChanges(doc);
      this.markDirty(doc, false);
    }
  }

  on_edits(m) {
    // edits of a rename in an open document: applied as the user's own, so they sync back
    const doc = this.docs.get(m.file);
    if (!doc) return;
    const state = this.stateOf(doc);
    const d = state.doc;
    const changes = m.changes.map(([l1, c1, l2, c2, text]) => ({
      from: d.line(l1).from + c1 - 1, to: d.line(l2).from + c2 - 1, insert: text,
    }));
    if (doc.file === this.current) this.view.dispatch({ changes });
    else {
      const tr = doc.state.update({ changes });
      doc.state = tr.state;
      doc.pending = doc.pending ? doc.pending.compose(tr.changes) : tr.changes;
      this.flushChanges(doc);
      this.markDirty(doc, true);
    }
  }

  on_live(m) {
    const doc = this.docs.get(m.file);
    if (!doc || doc.file !== this.current) return;
    this.view.dispatch({ effects: setLive.of(liveDecorations(this.view.state.doc, m.items)) });
    this.liveItems = m.items;
    if (this.bottomTab === "live") this.drawBottom();
  }

  on_events(m) {
    this.events = m.items;
    if (this.bottomTab === "events") this.drawBottom();
  }

  on_coverage(m) {
    this.coverage = m.files || {};
    this.applyCoverage();
  }

  on_notice(m) {
    this.flash(m.text);
  }

  on_debug(m) {
    this.debug.receive(m);
  }
}

if (!window.padtEditor) {
  window.padtEditor = new PadtEditor();
}
