"""The panel's HTML page: the goal form (the rqt plugin's X, Y, Ori spin boxes, Start, Cancel, the
controller checkbox, and Set pose: the same X, Y, Ori as rviz's 2D Pose Estimate) and the goal status beside the Meshcat view (an iframe).

The page does no validation of its own beyond what the inputs' min/max hint at: it sends what was
typed and shows the server's answer, so the rules live in one place (view/panel.py).
"""

from __future__ import annotations

import html

from .panel import ORI_RANGE, X_RANGE, Y_RANGE

_TEMPLATE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>
 body {{ margin: 0; font-family: sans-serif; display: flex; height: 100vh; }}
 #panel {{ width: 270px; padding: 12px; box-sizing: border-box; background: #f4f4f4; overflow-y: auto; }}
 #panel label {{ display: block; margin: 6px 0 2px; font-weight: bold; }}
 #panel input[type=number] {{ width: 100%; box-sizing: border-box; font-size: 14px; }}
 #panel button {{ margin: 10px 6px 0 0; font-size: 14px; padding: 4px 14px; }}
 #message {{ margin-top: 10px; min-height: 2em; color: #b00020; white-space: pre-wrap; }}
 #message.ok {{ color: #1b5e20; }}
 #status {{ font-size: 20px; font-weight: bold; margin-top: 4px; }}
 #status-text {{ font-size: 13px; color: #333; }}
 .small {{ font-size: 12px; color: #555; }}
 iframe {{ flex: 1; border: 0; height: 100vh; }}
</style></head>
<body>
<div id="panel">
 <h3 style="margin-top:0">Goal</h3>
 <div class="small" id="mode"></div>
 <label for="x">X (m)</label><input id="x" type="number" step="0.1" min="{x0}" max="{x1}" value="0">
 <label for="y">Y (m)</label><input id="y" type="number" step="0.1" min="{y0}" max="{y1}" value="0">
 <label for="ori">Ori (rad)</label><input id="ori" type="number" step="0.01" min="{o0}" max="{o1}" value="0">
 <div><button id="start">Start</button><button id="cancel">Cancel</button><button id="initialpose" title="X, Y, Ori as the robot's pose on /initialpose (a localiser such as amcl restarts there)">Set pose</button></div>
 <label><input id="controller" type="checkbox"> Controller enabled</label>
 <div class="small" id="controllers"></div>
 <div id="message"></div>
 <h3>Status</h3>
 <div id="status">-</div><div id="status-text"></div>
 <p class="small">robot <span id="robot">-</span></p>
 <p class="small">sim time <span id="sim-time">0.0</span> s, <span id="rtf">-</span>x real time</p>
 <p class="small" id="frames"></p>
</div>
<iframe id="meshcat" src="{meshcat}" title="Meshcat view"></iframe>
<script>
const $ = (id) => document.getElementById(id);
let lastShown = 0, checkboxBusy = false;
function say(text, ok) {{ $("message").textContent = text; $("message").className = ok ? "ok" : ""; }}
async function post(path, body) {{
  try {{
    const r = await fetch(path, {{method: "POST", headers: {{"Content-Type": "application/json"}},
                                 body: JSON.stringify(body)}});
    const data = await r.json();
    if (!r.ok) {{ say(data.error || ("error " + r.status), false); return null; }}
    say("sent (request " + data.queued + ")", true);
    return data.queued;
  }} catch (e) {{ say("the simulation is not reachable: " + e, false); return null; }}
}}
$("start").onclick = () => post("/api/goal", {{x: $("x").value, y: $("y").value, ori: $("ori").value}});
$("cancel").onclick = () => post("/api/cancel", {{}});
$("initialpose").onclick = () => post("/api/initialpose", {{x: $("x").value, y: $("y").value, ori: $("ori").value}});
$("controller").onchange = async () => {{
  checkboxBusy = true; await post("/api/controller", {{enable: $("controller").checked}});
  setTimeout(() => {{ checkboxBusy = false; }}, 1500);
}};
async function poll() {{
  try {{
    const s = await (await fetch("/api/state")).json();
    $("sim-time").textContent = s.time.toFixed(1);
    $("rtf").textContent = s.rtf == null ? "-" : s.rtf.toFixed(2);
    $("mode").textContent = s.mode || "";
    const f = s.frames;  // frames the view dropped so the simulation keeps real time
    if (f) $("frames").textContent = f.dropped ? "3-D view: " + f.sent + " frames, " + f.dropped +
        " dropped to keep real time" : "3-D view: " + f.sent + " frames";
    if (s.robot) $("robot").textContent = "(" + s.robot.map(v => v.toFixed(2)).join(", ") + ")";
    if (s.status) {{ $("status").textContent = s.status.name; $("status-text").textContent = s.status.text; }}
    $("controllers").textContent = s.controllers.map(c => c.name + ": " + c.state).join(", ");
    if (!checkboxBusy && s.controllers.length) $("controller").checked = s.controllers.some(c => c.state === "running");
    const a = s.last_action;
    if (a && a.id > lastShown) {{ lastShown = a.id; say(a.message, a.ok); }}
  }} catch (e) {{ }}
  setTimeout(poll, 300);
}}
poll();
</script>
</body></html>
"""


def render_page(meshcat_url: str, title: str) -> str:
    # The panel is served from 127.0.0.1; Meshcat is framed as "localhost" (the same server) so the
    # browser counts it as another site and renders it in a process of its own. Framed as the
    # same site, its WebGL drawing (software-rendered on machines without a GPU) starves the
    # panel: a click can take a minute in headless Chromium.
    meshcat_url = meshcat_url.replace("//127.0.0.1:", "//localhost:")
    return _TEMPLATE.format(
        title=html.escape(title),
        meshcat=html.escape(meshcat_url, quote=True),
        x0=X_RANGE[0],
        x1=X_RANGE[1],
        y0=Y_RANGE[0],
        y1=Y_RANGE[1],
        o0=ORI_RANGE[0],
        o1=ORI_RANGE[1],
    )
