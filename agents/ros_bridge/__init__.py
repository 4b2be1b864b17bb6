"""The ROS 2 bridge agent: chronav's world, social map, people and plans as ROS 2 topics over
Zenoh (rmw_zenoh's conventions), ``/goal_pose`` as a pose mission, and a ROS 2 robot driven by
chronav in ``--robot ros`` mode (docs/ros2.md)."""
