// The editor's page elements, made without a framework: the editor (editor.js) and its
// Debug panel (debugging.js) draw with these.

export function el(tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === "style") node.style.cssText = v;
    else if (k.startsWith("on")) node.addEventListener(k.slice(2), v);
    else node.setAttribute(k, v);
  }
  for (const c of children) node.append(c);
  return node;
}

export const BUTTON = "font:13px system-ui,sans-serif;padding:2px 9px;white-space:nowrap;border:1px solid #ced4da;border-radius:4px;background:#fff;cursor:pointer;";
export const TAB = "font:13px system-ui,sans-serif;padding:4px 10px;border:none;border-bottom:2px solid transparent;background:none;cursor:pointer;white-space:nowrap;";
