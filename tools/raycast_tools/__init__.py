"""raycast's Python tools: the independent half of the project's evidence.

Run them as `python -m raycast_tools COMMAND` (the list: `python -m raycast_tools --help`);
tools/venv.sh installs this package, editable, into the repository's .venv.

Commands (one module each): validate, validate_usd, bench, error_vs_time, make_fixtures,
make_quadric_fixtures, export_usd_fixtures, stiff_cases, tessellate, tessellation_check,
quadric_reference, random_quadric_scenes, usd_counts, thread_scaling.

Shared pieces (libraries, no command):

* paths: the repository root and finding the raycast binary;
* runner: running raycast (rays mode, `info`) and reading its outputs;
* rays: the validation rays and camera rays;
* cast: trimesh's float64 ray_triangle and Embree casts on a triangle soup;
* metrics: angles, error statistics, slopes;
* gltf_writer: the byte-exact glTF/GLB writer and fixture file writing;
* quadric_reference, tessellate: the object-space quadric reference and tessellations;
* usd_stage: opening a USD stage quietly and finding USD files;
* machine: what a report says about the machine it ran on.
"""
