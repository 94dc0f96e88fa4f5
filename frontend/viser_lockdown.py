"""What of viser the PADT's page does without. viser 1.1 opens a public tunnel to the UI
(share.viser.studio) for any websocket client that sends a `ShareUrlRequest`, logged in or
not; its panel offers that Share button and a settings popover (Dev Settings, the scene
tree, Save Canvas) to every visitor. The tunnel is refused on the server: hiding the
button would not stop a crafted message. The rest is hidden from the page, and a password
field is made a real password input (viser has none; a field masked by CSS alone shows
the password in Firefox). viser's page warns in a notification that stays until closed
when WebGL renders in software (headless browsers, VMs without a GPU); it covered the
editor's toolbar and the dialogs' titles, for a plant drawing that is optional now: it is
closed as it appears."""

from __future__ import annotations

import html
import itertools
import logging

import viser
from viser import _messages
from viser.infra import ClientId

from frontend import page_clicks, page_writer
from frontend.editor.messages import INPUT_LABEL

log = logging.getLogger("padt.ui")

PASSWORD_LABEL = "Password"  # every field so labelled is a password input
SETTINGS_BUTTON = "Save Canvas"  # a button of viser's settings: its stack is hidden
# The inputs through which page scripts talk to the server: never seen, whenever viser
# draws them (their own scripts hide them only once they first speak).
HIDDEN_INPUTS = (page_clicks.LABEL, INPUT_LABEL)
# viser's notifications about the browser's WebGL (BrowserWarning.tsx), by their titles
WEBGL_TITLES = ("Software WebGL rendering detected",)

# The header buttons of viser's panels: Share (hidden by the theme as well) and the one
# that unfolds the settings. The work area's Parameters tab uses the same icon, but is a
# tab.
_STYLE = (
    "<style>"
    "[data-dock-header] button:has(svg.tabler-icon-share),"
    "[data-dock-header] button:has(svg.tabler-icon-adjustments)"
    "{display:none !important}"
    "</style>"
)

# Installed once per page, and run again whenever viser draws something: every input
# labelled "Password" (the login card, the resource login, the login again after logging
# out) becomes type=password; React sets no type on viser's text inputs, so it keeps the
# one set here, and a field drawn anew is a new element (and every field is looked at
# again when one takes the focus, before anything is typed); the rows of the hidden inputs
# get display:none. viser's settings (Save Canvas, Dev Settings, the scene tree) are one
# stack in the panel, folded away but in the page and unfolded for a moment when the panel
# moves: it is hidden for good. A WebGL notification is hidden and closed (its close
# button: Mantine then drops it from its stack).
_HIDDEN = ",".join(f"'{label}'" for label in HIDDEN_INPUTS)
_WEBGL = ",".join(f"'{title}'" for title in WEBGL_TITLES)
_SCRIPT = (
    "if(!window.__padtPage){window.__padtPage=1;"
    f"var hidden=[{_HIDDEN}],webgl=[{_WEBGL}];"
    "var fix=function(){document.querySelectorAll('label').forEach(function(l){"
    "var t=l.textContent;if(t!=='" + PASSWORD_LABEL + "'&&hidden.indexOf(t)<0)return;"
    "var row=l.parentElement&&l.parentElement.parentElement&&l.parentElement.parentElement"
    ".parentElement;if(!row)return;"
    "if(hidden.indexOf(t)>=0){if(row.style.display!=='none')row.style.display='none';return}"
    "var input=row.querySelector('input');"
    "if(input&&input.type!=='password')input.type='password'});"
    "document.querySelectorAll('.mantine-Notification-root').forEach(function(n){"
    "if(n.dataset.padtGone)return;var title=n.querySelector('.mantine-Notification-title');"
    "if(!title||webgl.indexOf(title.textContent)<0)return;"
    "n.dataset.padtGone='1';n.style.display='none';"
    "var close=n.querySelector('.mantine-Notification-closeButton');if(close)close.click()});"
    "document.querySelectorAll('button').forEach(function(b){"
    f"if(b.textContent!=='{SETTINGS_BUTTON}')return;"
    "var stack=b.closest('.mantine-Stack-root');"
    "if(stack&&stack.style.display!=='none')stack.style.display='none'})};"
    "fix();new MutationObserver(fix).observe(document.body,{childList:true,subtree:true});"
    "document.addEventListener('focusin',fix,true)}"
)

# hidden: it takes no room at the top of the panel (a hidden image loads all the same)
PAGE_HTML = (
    f'<div style="display:none">{_STYLE}'
    f'<img alt="" src="data:," onerror="{html.escape(page_writer.SCRIPT + _SCRIPT)}"></div>'
)


def lock_down(server: viser.ViserServer) -> None:
    """No share tunnel for any client, and no Share button; the rest is `PAGE_HTML`, which
    each browser's GUI carries."""
    server.gui.configure_theme(show_share_button=False, show_logo=False, control_width="large")
    websocket = server._websock_server  # viser is pinned below 1.2
    websocket.unregister_handler(_messages.ShareUrlRequest)  # viser's opens the tunnel
    websocket.register_handler(_messages.ShareUrlRequest, _refuse_share_url)


_refused = itertools.count(1)


def _refuse_share_url(client_id: ClientId, _: _messages.ShareUrlRequest) -> None:
    number = next(_refused)
    if number & (number - 1) == 0:  # the 1st, 2nd, 4th, ...: a flood does not fill the log
        log.warning(
            "refused a share URL request (no. %d, from browser %s): the UI is never shared",
            number,
            client_id,
        )
