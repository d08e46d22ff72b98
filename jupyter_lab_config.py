"""JupyterLab for glu (`make lab`): the repository as root, the notebooks open as notebooks.

`make lab` runs `jupyter lab --config=jupyter_lab_config.py`. Double-clicking a notebook (a jupytext
`.py` file) opens it as a notebook, by the project's own settings in `jupyterlab/settings/overrides.json`
(nothing is written to your home folder). Saving keeps the `.py` file as it is in git: jupytext's settings
are in `pyproject.toml`. A notebook run from Lab writes into a new folder of its own,
`build/scratch/<notebook>/<date>-<time>/`; only `glu reproduce` publishes into `results/`, `recordings/`,
`models/` and `build/`.
"""

from pathlib import Path

ROOT = Path(__file__).resolve().parent
c = get_config()  # noqa: F821 - provided by Jupyter when it loads this file
c.ServerApp.root_dir = str(ROOT)
c.LabApp.app_settings_dir = str(ROOT / "jupyterlab" / "settings")
c.LabApp.default_url = "/lab/tree/notebooks"
c.ServerApp.ip = "127.0.0.1"  # this machine only
c.ServerApp.allow_root = True  # containers and CI machines often run as root
