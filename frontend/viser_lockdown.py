"""What of viser the PADT's page does without. viser 1.1 opens a public tunnel to the UI
(share.viser.studio) for any websocket client that sends a `ShareUrlRequest`, logged in or
not; its panel offers that Share button and a settings popover (Dev Settings, the scene
tree, Save Canvas) to every visitor. The tunnel is refused on the server: hiding the
button would not stop a crafted message. The rest is hidden from the page, and a password
field is made a real password input (viser has none; a field masked by CSS alone shows
the password in Firefox)."""

from __future__ import annotations

import html
import itertools
import logging

import viser
from viser import _messages
from viser.infra import ClientId

log = logging.getLogger("padt.ui")

PASSWORD_LABEL = "Password"  # every field so labelled is a password input
SETTINGS_BUTTON = "Save Canvas"  # a button of viser's settings: its stack is hidden

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
# again when one takes the focus, before anything is typed). viser's settings (Save Canvas,
# Dev Settings, the scene tree) are one stack in the panel, folded away but in the page
# and unfolded for a moment when the panel moves: it is hidden for good.
_SCRIPT = (
    "if(!window.__padtPage){window.__padtPage=1;"
    "var fix=function(){document.querySelectorAll('label').forEach(function(l){"
    f"if(l.textContent!=='{PASSWORD_LABEL}')return;"
    "var row=l.parentElement&&l.parentElement.parentElement&&l.parentElement.parentElement"
    ".parentElement;var input=row&&row.querySelector('input');"
    "if(input&&input.type!=='password')input.type='password'});"
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
    f'<img alt="" src="data:," onerror="{html.escape(_SCRIPT)}"></div>'
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
