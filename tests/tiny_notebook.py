"""The smallest notebook ``glu reproduce`` accepts: a manifest naming one figure, the parameters cell, and a
cell that writes the figure ``a`` (PNG and SVG) holding the text ``run SEED``, so a test can tell which run
published it. Used by the publication and hostile-input tests."""

TINY_NOTEBOOK = """# ---
# jupyter:
#   glu:
#     about: a test notebook
#     figures:
#     - a
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

# %%
from pathlib import Path
Path(out_dir, "figures").mkdir(parents=True, exist_ok=True)
for ext in ("png", "svg"):
    Path(out_dir, "figures", f"a.{ext}").write_text(f"run {seed}")
"""
