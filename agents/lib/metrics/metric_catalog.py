"""Every navigation metric chronav reports: one name, one definition, one unit, one source.

Why a catalogue: `chronav metrics`, the demo's table and the `evaluate` table and report are what a
researcher copies into a paper, so a metric must be called the same everywhere, carry its unit, and
say where its definition comes from - the seed papers (``seed``), HuNavSim's evaluator
(``HuNavSim``: N. Pérez-Higueras et al., "HuNavSim", IEEE RA-L 8(11) 2023, and its
``hunav_evaluator/hunav_metrics.py``; the papers it cites for each metric are in docs/metrics.md) or
chronav itself (``chronav``).  ``docs/metrics.md`` is this table in prose; a unit test checks that
the two list the same metrics.

Keys are the JSON keys of ``chronav metrics --json`` (``--definitions published``), nested keys
joined by a dot (``dynamic.min_distance_to_people_m``), which are also the columns of the
``evaluate`` table.  ``hunav`` is the key HuNavSim's evaluator uses for the same metric (the keys of
``--definitions hunav --json``); empty when HuNavSim has no such metric.
"""

from __future__ import annotations

from dataclasses import dataclass

SOURCES: tuple[str, ...] = ("seed", "HuNavSim", "chronav")


@dataclass(frozen=True)
class MetricDef:
    """One metric: its key, the label tables print, unit, source and definition (one sentence)."""

    key: str
    label: str
    unit: str
    source: str
    definition: str
    hunav: str = ""

    def heading(self) -> str:
        """The table label with its unit, e.g. ``path length d_t (m)``."""
        return f"{self.label} ({self.unit})" if self.unit else self.label


_D = MetricDef
CATALOG: tuple[MetricDef, ...] = (
    # --- the seeds' tables (metrics.py), on the driven path -------------------------------------
    _D("distance_travelled_m", "path length d_t", "m", "seed",
       "length of the polyline through the robot's samples", "path_length"),
    _D("duration_s", "time to goal tau", "s", "seed",
       "last sample's time minus the first's", "time_to_reach_goal"),
    _D("cumulative_heading_change_rad", "cumulative heading change CHC", "rad", "seed",
       "sum over consecutive samples of |heading change| wrapped to [-pi, pi)", "cumulative_heading_changes"),
    _D("d_min_person_m.*", "d_min to {} at the start, path to centre", "m", "seed",
       "smallest distance from the driven path to where the person stood when the mission started "
       "(their centre, no radius subtracted)"),
    _D("d_min_object_m.*", "d_min to {}, path to footprint", "m", "seed",
       "smallest distance from the driven path to the object's footprint"),
    _D("psi_zone_percent.*", "Psi {} zone, seeds' contours", "% of path", "seed",
       "share of the path length inside that exclusive band of the people's zone contours (intimate, "
       "personal, social density levels; public the rest) as the planner drew them at the mission's start: "
       "the adapted personal spaces when adaptation is on"),
    _D("psi_unadapted_zone_percent.*", "Psi {} zone, unadapted contours", "% of path", "chronav",
       "as Psi, on the zone contours the people's spaces would have without the wall adaptation "
       "(equal to Psi when adaptation is off or changed nothing)"),
    _D("psi_object_percent.*", "Psi {}'s interaction space", "% of path", "seed",
       "share of the path length inside that object's interaction space"),
    # --- among the moving people (dynamic_metrics.py; people.csv needed) --------------------------
    _D("dynamic.min_distance_to_people_m", "minimum distance to people, body edges", "m", "HuNavSim",
       "min over samples and people of max(0, centre distance - robot radius - person radius)",
       "minimum_distance_to_people"),
    _D("dynamic.max_distance_to_people_m", "maximum distance to people, body edges", "m", "HuNavSim",
       "max over samples and people of max(0, centre distance - robot radius - person radius)",
       "maximum_distance_to_people"),
    _D("dynamic.avg_distance_to_closest_person_m", "average distance to the closest person, body edges", "m",
       "HuNavSim", "mean over samples with people of the closest person's max(0, centre distance - both radii)",
       "avg_distance_to_closest_person"),
    _D("dynamic.intimate_intrusions_percent", "intimate-space intrusions, Hall < 0.45 m", "% of samples",
       "HuNavSim", "share of samples whose closest person's body-edge distance is below 0.45 m",
       "intimate_space_intrusions"),
    _D("dynamic.personal_intrusions_percent", "personal-space intrusions, Hall 0.45-1.2 m", "% of samples",
       "HuNavSim", "share of samples whose closest person's body-edge distance is in [0.45, 1.2) m",
       "personal_space_intrusions"),
    _D("dynamic.social_intrusions_percent", "social-space intrusions, Hall 1.2-3.6 m", "% of samples",
       "HuNavSim", "share of samples whose closest person's body-edge distance is in [1.2, 3.6) m",
       "social_space_intrusions"),
    _D("dynamic.intrusions_per_person.*", "Hall-band intrusions by {}", "% of samples", "chronav",
       "the three intrusion shares with that person's own body-edge distance"),
    _D("dynamic.group_intimate_intrusions_percent", "group intimate-space intrusions, < 0.45 m",
       "% of samples", "HuNavSim",
       "share of samples whose closest group centre (members moved 1.5 m along their heading, averaged) "
       "is nearer than 0.45 m to the robot's edge, clipped at 0 (groups of two or more, regrouped every sample)",
       "group_intimate_space_intrusions"),
    _D("dynamic.group_personal_intrusions_percent", "group personal-space intrusions, 0.45-1.2 m",
       "% of samples", "HuNavSim", "as the group intimate share, in [0.45, 1.2) m",
       "group_personal_space_intrusions"),
    _D("dynamic.group_social_intrusions_percent", "group social-space intrusions, 1.2-3.6 m",
       "% of samples", "HuNavSim", "as the group intimate share, in [1.2, 3.6) m",
       "group_social_space_intrusions"),
    _D("dynamic.intrusions_per_group.*", "Hall-band intrusions of group {}", "% of samples", "chronav",
       "the group shares with that group's own centre"),
    _D("dynamic.robot_on_person_collisions", "collisions, robot on person", "count", "chronav",
       "contacts (body-edge distance < 0.02 m), each counted once, blamed on the robot when it approached "
       "faster", "robot_on_person_collision"),
    _D("dynamic.person_on_robot_collisions", "collisions, person on robot", "count", "chronav",
       "contacts each counted once, blamed on the person when they approached faster",
       "person_on_robot_collision"),
    _D("dynamic.robot_intimate_entries", "entries into a person's intimate zone, by the robot", "count",
       "chronav", "times the robot's centre entered someone's intimate zone as the social map draws it "
       "(level 0.8 of their stretched, role-scaled space) while the robot was the one approaching"),
    _D("dynamic.time_not_moving_s", "time not moving", "s", "HuNavSim",
       "total time of the intervals in which the robot's speed < 0.01 m/s and |angular speed| < 0.02 rad/s "
       "(an interval over 5x the median sampling is a gap between missions and does not count)",
       "time_not_moving"),
    _D("dynamic.avg_robot_linear_speed_mps", "average linear speed", "m/s", "HuNavSim",
       "mean over samples of the robot's speed (forward differences of its positions)",
       "avg_robot_linear_speed"),
    _D("dynamic.avg_robot_angular_speed_radps", "average angular speed", "rad/s", "HuNavSim",
       "mean over samples of |the robot's turn rate| (forward differences of its heading)",
       "avg_robot_angular_speed"),
    _D("dynamic.avg_acceleration_mps2", "average acceleration", "m/s^2", "HuNavSim",
       "mean over intervals of |change of linear speed| / interval (SocNavBench)", "avg_acceleration"),
    _D("dynamic.avg_jerk_mps3", "average jerk", "m/s^3", "HuNavSim",
       "mean over consecutive intervals of |change of acceleration| / mean interval (SocNavBench)",
       "avg_overacceleration"),
    _D("dynamic.avg_pedestrian_speed_mps", "average pedestrian speed", "m/s", "HuNavSim",
       "mean over samples and people of a person's speed", "avg_pedestrian_velocity"),
    _D("dynamic.avg_closest_pedestrian_speed_mps", "average closest-pedestrian speed", "m/s", "HuNavSim",
       "mean over samples of the speed of the person closest to the robot", "avg_closest_pedestrian_velocity"),
    _D("dynamic.social_force_on_robot", "social force on the robot", "m/s^2, summed over samples",
       "HuNavSim", "sum over samples and people of |the social force the person exerts on the robot| "
       "(lightsfm model, HuNavSim's parameters: A 2.1, lambda 2, gamma 0.35, n 2, n' 3)", "social_force_on_robot"),
    _D("dynamic.social_force_on_people", "social force on people", "m/s^2, summed over samples",
       "HuNavSim", "sum over samples and people of |the social force the robot exerts on the person|",
       "social_force_on_agents"),
    _D("dynamic.obstacle_force_on_robot", "obstacle force on the robot", "m/s^2, summed over samples",
       "HuNavSim", "sum over samples of 10 exp(-(distance to the nearest wall or object - robot radius) / 0.2)",
       "obstacle_force_on_robot"),
    _D("dynamic.obstacle_force_on_people", "obstacle force on people", "m/s^2, summed over samples",
       "HuNavSim", "sum over samples of the mean over people of 10 exp(-(distance to the nearest wall or "
       "object - person radius) / 0.2)", "obstacle_force_on_agents"),
    _D("dynamic.social_work", "social work", "m/s^2, summed over samples", "HuNavSim",
       "sum over samples of |sum of social forces on the robot| + |obstacle force on it| + sum of the "
       "moduli of the forces it exerts on people (social_force_window_planner)", "social_work"),
    # --- towards the goal (needs the goal: a pose mission's target or --goal) ---------------------
    _D("dynamic.completed", "completed", "yes/no", "HuNavSim",
       "1 when the last sample is within the goal tolerance (+0.05 m) of the target", "completed"),
    _D("dynamic.minimum_distance_to_target_m", "minimum distance to target", "m", "HuNavSim",
       "the closest the robot's centre came to the target", "minimum_distance_to_target"),
    _D("dynamic.final_distance_to_target_m", "final distance to target", "m", "HuNavSim",
       "distance from the last sample to the target", "final_distance_to_target"),
)

BY_KEY: dict[str, MetricDef] = {m.key: m for m in CATALOG}
BY_HUNAV: dict[str, MetricDef] = {m.hunav: m for m in CATALOG if m.hunav}
HUNAV_KEYS: tuple[str, ...] = tuple(m.hunav for m in CATALOG if m.hunav)


def lookup(column: str) -> tuple[MetricDef, str] | None:
    """The definition of a JSON key / table column and the name filled into its ``{}`` (a person,
    object, band or group), or None for a column that is not a metric."""
    if column in BY_KEY:
        return BY_KEY[column], ""
    for metric in CATALOG:
        if metric.key.endswith(".*") and column.startswith(metric.key[:-1]):
            return metric, column[len(metric.key) - 1:]
    return None


def column_label(column: str) -> str:
    """A reader's name for a metric column, with its unit (unknown columns keep their name)."""
    found = lookup(column)
    if found is None:
        return column
    metric, name = found
    label = metric.label.format(name.replace(".", " ")) if "{}" in metric.label else metric.label
    return f"{label} ({metric.unit})" if metric.unit else label
