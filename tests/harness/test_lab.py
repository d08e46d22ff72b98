"""`make lab`: a real JupyterLab, configured by the project, opens the notebooks as notebooks and saves them
unchanged."""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from glu import paths

ROOT = paths.PROJECT_ROOT
CONFIG = ROOT / "jupyter_lab_config.py"
TOKEN = "glu-test-token"

pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (the test extra installs it)")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url: str) -> dict:
    req = urllib.request.Request(url, headers={"Authorization": f"token {TOKEN}"})
    with urllib.request.urlopen(req, timeout=10) as r:
        return json.loads(r.read())


def _put(url: str, body: dict) -> dict:
    data = json.dumps(body).encode()
    req = urllib.request.Request(
        url,
        data=data,
        method="PUT",
        headers={"Authorization": f"token {TOKEN}", "Content-Type": "application/json"},
    )
    with urllib.request.urlopen(req, timeout=10) as r:
        return json.loads(r.read())


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """JupyterLab with the project's configuration, on a copy of the notebooks (so saving cannot harm
    them)."""
    root = tmp_path_factory.mktemp("lab-root")
    shutil.copytree(ROOT / "notebooks", root / "notebooks", ignore=shutil.ignore_patterns("*.ipynb"))
    shutil.copy(ROOT / "pyproject.toml", root / "pyproject.toml")  # jupytext's settings
    port = _free_port()
    home = tmp_path_factory.mktemp("home")  # nothing of the user's own settings is read or written
    env = {
        "HOME": str(home),
        "JUPYTER_CONFIG_DIR": str(home / ".jupyter"),
        "JUPYTERLAB_SETTINGS_DIR": str(home / "lab-user-settings"),
        "PATH": "/usr/bin:/bin",
        "JUPYTER_PLATFORM_DIRS": "1",
    }
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "jupyterlab",
            f"--config={CONFIG}",
            "--no-browser",
            f"--port={port}",
            f"--ServerApp.root_dir={root}",
            f"--IdentityProvider.token={TOKEN}",
            "--ServerApp.port_retries=0",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=env,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                _get(f"{base}/api/status")
                break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    err = proc.stderr.read().decode(errors="replace")[-2000:] if proc.stderr else ""
                    pytest.fail(f"JupyterLab did not start: {err}")
                time.sleep(0.3)
        yield base, root
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()


def test_the_config_roots_lab_at_the_repository():
    namespace = {}

    class _Config(dict):
        def __getattr__(self, key):
            return self.setdefault(key, _Config())

        def __setattr__(self, key, value):
            self[key] = value

    config = _Config()
    namespace["get_config"] = lambda: config
    namespace["__file__"] = str(CONFIG)  # as Jupyter loads a config file
    exec(compile(CONFIG.read_text(), str(CONFIG), "exec"), namespace)
    assert Path(config["ServerApp"]["root_dir"]) == ROOT
    assert config["LabApp"]["default_url"] == "/lab/tree/notebooks"
    assert Path(config["LabApp"]["app_settings_dir"]) == ROOT / "jupyterlab" / "settings"


def test_python_files_open_as_notebooks_by_the_projects_settings(lab):
    base, _ = lab
    doc = _get(f"{base}/lab/api/settings/@jupyterlab/docmanager-extension:plugin")
    assert doc["schema"]["properties"]["defaultViewers"]["default"] == {"python": "Jupytext Notebook"}
    model = _get(f"{base}/api/contents/notebooks/07_glu2017_figures.py?content=1")
    assert model["type"] == "notebook"  # jupytext's contents manager serves the .py as a notebook
    tags = [c["metadata"].get("tags", []) for c in model["content"]["cells"]]
    assert ["parameters"] in tags


@pytest.mark.parametrize("name", ["02_hmm_training", "08_tcds_figures"])
def test_saving_from_lab_keeps_the_file_as_it_is_in_git(lab, name):
    base, root = lab
    path = root / "notebooks" / f"{name}.py"
    before = path.read_bytes()
    assert before == (ROOT / "notebooks" / f"{name}.py").read_bytes()
    model = _get(f"{base}/api/contents/notebooks/{name}.py?content=1")
    nb = model["content"]
    nb["metadata"]["language_info"] = {"name": "python", "version": "3.11"}
    for i, cell in enumerate(nb["cells"]):  # what a session in Lab leaves on a notebook
        if cell["cell_type"] == "code":
            cell["execution_count"] = i
            cell["outputs"] = [{"output_type": "stream", "name": "stdout", "text": "some output\n"}]
            cell["metadata"]["scrolled"] = True
            cell["metadata"]["execution"] = {"iopub.status.idle": "2026-11-23T00:00:00Z"}
    saved = _put(
        f"{base}/api/contents/notebooks/{name}.py", {"type": "notebook", "format": "json", "content": nb}
    )
    assert saved["path"] == f"notebooks/{name}.py"
    assert path.read_bytes() == before, "saving from JupyterLab changed the notebook's source"
    assert not list(path.parent.glob("*.ipynb"))  # and no paired .ipynb appears


def _post(url: str, body: dict) -> dict:
    req = urllib.request.Request(
        url,
        data=json.dumps(body).encode(),
        method="POST",
        headers={"Authorization": f"token {TOKEN}", "Content-Type": "application/json"},
    )
    with urllib.request.urlopen(req, timeout=60) as r:
        return json.loads(r.read())


def _delete(url: str) -> None:
    req = urllib.request.Request(url, method="DELETE", headers={"Authorization": f"token {TOKEN}"})
    with urllib.request.urlopen(req, timeout=30):
        pass


def _message(msg_type: str, content: dict, session: str) -> dict:
    import uuid

    return {
        "header": {
            "msg_id": uuid.uuid4().hex,
            "msg_type": msg_type,
            "username": "test",
            "session": session,
            "date": "2026-11-27T00:00:00Z",
            "version": "5.3",
        },
        "parent_header": {},
        "metadata": {},
        "content": content,
        "channel": "shell",
        "buffers": [],
    }


def _run_in_a_kernel(base: str, kernel_id: str, code: str) -> tuple[dict, list[dict], int]:
    """Over the kernel's websocket, as Lab does: its language_info, then ``code`` executed: its outputs, as
    nbformat stores them, and its execution count."""
    import asyncio
    import uuid

    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    session = uuid.uuid4().hex

    async def talk() -> tuple[dict, list[dict], int]:
        url = base.replace("http://", "ws://") + f"/api/kernels/{kernel_id}/channels?session_id={session}"
        ws = await websocket_connect(HTTPRequest(url, headers={"Authorization": f"token {TOKEN}"}))
        try:

            async def reply_to(msg: dict, collect: list | None = None) -> dict:
                ws.write_message(json.dumps(msg))
                msg_id, reply, idle = msg["header"]["msg_id"], None, False
                while reply is None or not idle:
                    raw = await asyncio.wait_for(ws.read_message(), timeout=120)
                    m = json.loads(raw)
                    if m.get("parent_header", {}).get("msg_id") != msg_id:
                        continue
                    kind = m["header"]["msg_type"]
                    if m["channel"] == "shell":
                        reply = m
                    elif kind == "status" and m["content"]["execution_state"] == "idle":
                        idle = True
                    elif collect is not None and kind in ("stream", "execute_result", "display_data"):
                        collect.append(m)
                return reply

            info = await reply_to(_message("kernel_info_request", {}, session))
            outputs: list[dict] = []
            done = await reply_to(
                _message("execute_request", {"code": code, "silent": False, "store_history": True}, session),
                outputs,
            )
        finally:
            ws.close()
        cells = []
        for m in outputs:
            kind, c = m["header"]["msg_type"], m["content"]
            if kind == "stream":
                cells.append({"output_type": "stream", "name": c["name"], "text": c["text"]})
            else:
                out = {"output_type": kind, "data": c["data"], "metadata": c.get("metadata", {})}
                if kind == "execute_result":
                    out["execution_count"] = c["execution_count"]
                cells.append(out)
        return info["content"]["language_info"], cells, done["content"]["execution_count"]

    return asyncio.run(talk())


@pytest.mark.parametrize("name", ["02_hmm_training", "08_tcds_figures"])
def test_saving_from_lab_after_a_kernel_ran_a_cell_keeps_the_file_as_it_is_in_git(lab, name):
    """As a session in Lab: a real kernel starts for the notebook and runs a cell; Lab then writes the
    kernel's spec (its display name) and language_info into the notebook's metadata and saves. The file is
    unchanged."""
    base, root = lab
    path = root / "notebooks" / f"{name}.py"
    before = path.read_bytes()
    assert before == (ROOT / "notebooks" / f"{name}.py").read_bytes()
    session = _post(
        f"{base}/api/sessions",
        {
            "path": f"notebooks/{name}.py",
            "type": "notebook",
            "name": f"{name}.py",
            "kernel": {"name": "python3"},
        },
    )
    try:
        language_info, outputs, count = _run_in_a_kernel(
            base, session["kernel"]["id"], "import sys\nprint('ran in', sys.implementation.name)\n6 * 7"
        )
        spec = _get(f"{base}/api/kernelspecs")["kernelspecs"][session["kernel"]["name"]]["spec"]
    finally:
        _delete(f"{base}/api/sessions/{session['id']}")
    assert any(o.get("data", {}).get("text/plain") == "42" for o in outputs), outputs
    model = _get(f"{base}/api/contents/notebooks/{name}.py?content=1")
    nb = model["content"]
    # what Lab's notebook panel sets once its kernel is ready, from the kernel's spec and its kernel_info
    nb["metadata"]["kernelspec"] = {
        "name": session["kernel"]["name"],
        "display_name": spec["display_name"],
        "language": spec["language"],
    }
    nb["metadata"]["language_info"] = language_info
    first = next(c for c in nb["cells"] if c["cell_type"] == "code")
    first["outputs"], first["execution_count"] = outputs, count
    saved = _put(
        f"{base}/api/contents/notebooks/{name}.py", {"type": "notebook", "format": "json", "content": nb}
    )
    assert saved["path"] == f"notebooks/{name}.py"
    assert path.read_bytes() == before, (
        "saving from JupyterLab after running a kernel changed the notebook's source"
    )
    assert not list(path.parent.glob("*.ipynb"))
