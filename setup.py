"""Build script shared by pip (PEP 517, metadata in pyproject.toml) and colcon (ament_python).

colcon's ament_python build still drives ``setup.py``; the data files below give the ROS layout
(share/bt_nav/{package.xml,trees,launch,config} and the ament index marker), while the
console scripts (declared in pyproject.toml) land in lib/bt_nav through setup.cfg, so that
``ros2 run bt_nav executive`` works.
"""

from glob import glob

from setuptools import find_packages, setup
from setuptools.dist import Distribution

PACKAGE = "bt_nav"


class ColconDistribution(Distribution):
    """Keeps ``python_requires`` a plain string, which colcon needs.

    colcon (colcon-python-setup-py) reads the configured distribution back with
    ``ast.literal_eval(repr(dist.__dict__))``, and setuptools stores pyproject's ``requires-python``
    as a ``SpecifierSet``, whose repr is no literal: ``colcon build`` then fails with "invalid syntax".
    """

    def parse_config_files(self, *args, **kwargs):  # noqa: D102
        super().parse_config_files(*args, **kwargs)
        for owner in (self, self.metadata):
            if getattr(owner, "python_requires", None) is not None:
                owner.python_requires = str(owner.python_requires)

setup(
    name=PACKAGE,
    # bt_nav (mission core, ROS edge, commands) and the simulator package bt_nav_sim, which lives
    # under sim/ so that it can only be imported by its installed name.
    packages=find_packages(include=["bt_nav", "bt_nav.*"]) + find_packages("sim", include=["bt_nav_sim*"]),
    package_dir={"bt_nav_sim": "sim/bt_nav_sim"},
    package_data={"bt_nav_sim": ["worlds/*.yaml"], "bt_nav": ["grading/*.yaml"]},  # Gradescope's default weights
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/trees", glob("trees/*.xml")),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
    ],
    zip_safe=False,
    distclass=ColconDistribution,
)
