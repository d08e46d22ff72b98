"""Sphinx configuration of glu's documentation site (built by glu.run.site, never by hand).

The sources (the index, the executed notebooks, the docs pages, the API pages) are assembled by
:func:`glu.run.site.build_site` in a folder of their own; this configuration and its static files ship with
the package. The notebooks are shown as ``glu reproduce`` executed them: never run again.
"""

project = "glu"
author = "the glu developers"
copyright = "the glu developers (MIT)"

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "glu.run.site_api",  # references to re-exported and short glu names linked; a broken one warns
    "glu.run.site_math",  # formulas as MathML, written at build time (MathJax would come from the web)
]
html_math_renderer = "mathml"
# quotes and ellipses typeset, dashes left alone: `--data` stays two hyphens wherever it is written
smartquotes_action = "qe"
exclude_patterns = ["_build", ".doctrees", "**.ipynb_checkpoints"]

# the notebooks: their outputs as executed by `glu reproduce`; figures with their captions (glu.run.site)
nb_execution_mode = "off"
nb_render_plugin = "glu"
nb_output_stderr = "show"
myst_heading_anchors = 3
myst_enable_extensions = ["attrs_inline", "colon_fence", "dollarmath", "html_image"]
myst_dmath_double_inline = True
suppress_warnings = ["mystnb.unknown_mime_type"]  # widget views: a live kernel's, shown as text here

# the API reference, from the numpydoc docstrings
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": True, "member-order": "bysource"}
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented_params"
autodoc_preserve_defaults = True
autodoc_use_type_comments = False  # glu annotates; looking for type comments took ~10 % of a build
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_ivar = True
napoleon_use_rtype = False
add_module_names = False

html_theme = "pydata_sphinx_theme"
html_title = "glu"
html_static_path = ["_static"]
html_css_files = ["glu.css"]
html_js_files = ["glu.js"]
html_show_sourcelink = False
html_copy_source = False
html_last_updated_fmt = None
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
    "use_edit_page_button": False,
    "show_version_warning_banner": False,
}
html_sidebars = {"index": [], "api": []}

html_context = {"default_mode": "light"}
html_domain_indices = False  # the API page is the index of the modules
