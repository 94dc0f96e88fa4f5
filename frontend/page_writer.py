"""How the page's own scripts tell the server something (a click viser does not report,
the editor's queue of messages): as viser's own message for a hidden input, sent past the
throttle of the panel's inputs.

viser's panel sends the values of all its inputs, and the presses of its buttons, through
one sender (`useThrottledMessageSender(50)` in its Generated.tsx), which within 50 ms keeps
only the newest message. A script that typed its report into a hidden input competed there
with the user: a report dropped a value typed or a press, or a value typed or a press the
report (a lost click on the project tree: CI of stops 46 to 48). So a report does not pass
that sender. viser hands every message to its websocket worker as `{type: "send",
message}`; the script below remembers the worker at the first such message and posts each
report to it, at once, as the `GuiUpdateMessage` the hidden input itself would send (an
input's id is its label's `for`). Until viser has sent anything (the worker is not known
yet) a report is typed into its input, as the user would.

What the user does stays viser's: a value typed and a button pressed within 50 ms of each
other can still drop one (the sender's rule); pressing the button a moment later sends it.
A press held back or a value sent twice instead made the server see them out of order.

The server reads a report like any input's value from a browser, as untrusted text."""

from __future__ import annotations

# Installed once per page, before the scripts that write (they are drawn after it):
# `window.__padtWrite(label, value)` with the label element of a hidden input.
SCRIPT = (
    "if(!window.__padtWrite){var worker=null,post=Worker.prototype.postMessage;"
    "Worker.prototype.postMessage=function(d){"
    "if(d&&d.type==='send')worker=this;return post.apply(this,arguments)};"
    "window.__padtWrite=function(label,value){"
    "if(worker&&label.htmlFor){worker.postMessage({type:'send',message:{"
    "type:'GuiUpdateMessage',uuid:label.htmlFor,updates:{value:value}}});return}"
    "var row=label.parentElement.parentElement.parentElement;"
    "var input=row&&row.querySelector('input');if(!input)return;"
    "Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value').set.call("
    "input,value);input.dispatchEvent(new Event('input',{bubbles:true}))}}"
)
