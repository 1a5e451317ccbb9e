"""The link layer: the driver interface every robot implements (:mod:`.interface`), the drivers by
name (:mod:`.drivers`), the line protocol, its authentication and its client (:mod:`.protocol`,
:mod:`.auth`, :mod:`.line_client`), and ROS 2 through rosbridge (:mod:`.ros2`,
:mod:`.ros2_messages`)."""
