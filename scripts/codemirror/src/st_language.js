// Structured Text and textual SFC for CodeMirror: highlighting by a stream tokenizer
// (keywords are case-insensitive, as IEC 61131-3 says), and folding from a line that opens a
// block to the line of its END_ keyword.
import { StreamLanguage, foldService } from "@codemirror/language";

const KEYWORDS = new Set(
  (
    "program end_program function end_function function_block end_function_block " +
    "configuration end_configuration resource end_resource task with on " +
    "var var_input var_output var_in_out var_global var_external var_temp var_access " +
    "var_config end_var constant retain non_retain at " +
    "type end_type struct end_struct array of string wstring pointer ref_to ref " +
    "if then elsif else end_if case end_case for to by do end_for while end_while " +
    "repeat until end_repeat exit continue return " +
    "step initial_step end_step transition from end_transition action end_action " +
    "method end_method property end_property interface end_interface extends implements " +
    "public private protected internal final abstract this super " +
    "and or xor not mod true false"
  ).split(" ")
);

const TYPES = new Set(
  (
    "bool byte word dword lword sint int dint lint usint uint udint ulint real lreal " +
    "time ltime date tod time_of_day dt date_and_time char wchar"
  ).split(" ")
);

// a typed literal or a based number: T#5s, TIME#1h2m, 16#FF, INT#-5, DT#2024-01-01-10:00
const TYPED_LITERAL = /^[A-Za-z_]+#[-+]?[\w.:\-]*/;
const NUMBER = /^(\d[\d_]*(\.[\d_]+)?([eE][-+]?\d+)?)/;

function tokenize(stream, state) {
  if (state.comment) {
    return continueComment(stream, state);
  }
  if (stream.eatSpace()) return null;
  if (stream.match("(*")) {
    state.comment = 1;
    return continueComment(stream, state);
  }
  if (stream.match("//")) {
    stream.skipToEnd();
    return "comment";
  }
  if (stream.peek() === "{") {
    stream.skipTo("}") ? stream.next() : stream.skipToEnd();
    return "meta";
  }
  const quote = stream.peek();
  if (quote === "'" || quote === '"') {
    stream.next();
    while (!stream.eol()) {
      const c = stream.next();
      if (c === "$") stream.next();
      else if (c === quote) break;
    }
    return "string";
  }
  if (stream.match(TYPED_LITERAL)) return "number";
  if (stream.match(NUMBER)) return "number";
  if (stream.match(/^[A-Za-z_]\w*/)) {
    const word = stream.current().toLowerCase();
    if (KEYWORDS.has(word)) return "keyword";
    if (TYPES.has(word)) return "typeName";
    return stream.peek() === "(" ? "function" : "variableName";
  }
  if (stream.match(/^(:=|=>|<=|>=|<>|\*\*|[-+*\/=<>&])/)) return "operator";
  stream.next();
  return null;
}

function continueComment(stream, state) {
  // IEC comments do not nest in most tools; a "(*" inside one is text
  while (!stream.eol()) {
    if (stream.match("*)")) {
      state.comment = 0;
      return "comment";
    }
    stream.next();
  }
  return "comment";
}

export const structuredText = StreamLanguage.define({
  name: "structured-text",
  startState: () => ({ comment: 0 }),
  copyState: (s) => ({ comment: s.comment }),
  token: tokenize,
  languageData: {
    commentTokens: { line: "//", block: { open: "(*", close: "*)" } },
  },
});

// The blocks that fold, by the keyword that opens them and the one that ends them.
const BLOCKS = [
  ["program", "end_program"],
  ["function_block", "end_function_block"],
  ["function", "end_function"],
  ["configuration", "end_configuration"],
  ["resource", "end_resource"],
  ["method", "end_method"],
  ["property", "end_property"],
  ["interface", "end_interface"],
  ["action", "end_action"],
  ["initial_step", "end_step"],
  ["step", "end_step"],
  ["transition", "end_transition"],
  ["type", "end_type"],
  ["struct", "end_struct"],
  ["var_input", "end_var"],
  ["var_output", "end_var"],
  ["var_in_out", "end_var"],
  ["var_global", "end_var"],
  ["var_external", "end_var"],
  ["var_temp", "end_var"],
  ["var", "end_var"],
  ["if", "end_if"],
  ["case", "end_case"],
  ["for", "end_for"],
  ["while", "end_while"],
  ["repeat", "end_repeat"],
];
const MAX_FOLD_LINES = 20000;
const VAR_SECTIONS = new Set(BLOCKS.filter(([, close]) => close === "end_var").map(([open]) => open));

function firstWord(text) {
  const m = /^\s*([A-Za-z_]+)/.exec(text);
  return m ? m[1].toLowerCase() : "";
}

function words(text) {
  // the words of a line outside its strings and comments, lower case
  const cut = text.replace(/'[^']*'|"[^"]*"|\(\*.*?\*\)|\/\/.*$/g, " ");
  return cut.toLowerCase().match(/[a-z_]+/g) || [];
}

export const stFolding = foldService.of((state, lineStart, lineEnd) => {
  const line = state.doc.lineAt(lineStart);
  const opener = firstWord(line.text);
  const block = BLOCKS.find(([open]) => open === opener);
  if (!block) return null;
  const [open, close] = block;
  let depth = 0;
  const last = Math.min(state.doc.lines, line.number + MAX_FOLD_LINES);
  for (let n = line.number; n <= last; n++) {
    const text = state.doc.line(n).text;
    for (const w of words(text)) {
      if (w === open || (close === "end_var" && VAR_SECTIONS.has(w))) depth++;
      else if (w === close) depth--;
    }
    if (depth <= 0) {
      if (n <= line.number + 1) return null;
      return { from: lineEnd, to: state.doc.line(n - 1).to };
    }
  }
  return null;
});
