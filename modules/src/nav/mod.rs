//! Navigation algorithms: localization, mapping, planning, obstacle avoidance, goal sequencing.
