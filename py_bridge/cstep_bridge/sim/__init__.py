"""The simulated worlds, in PyBullet: what the drone arena and the point maze share
(:mod:`~cstep_bridge.sim.world`), the drone's world as the paper states it
(:mod:`~cstep_bridge.sim.paper_world`) and its simulation (:mod:`~cstep_bridge.sim.drone`), the
maze's layout (:mod:`~cstep_bridge.sim.maze_layout`) and its simulation
(:mod:`~cstep_bridge.sim.maze`), and the Husky in its hall (:mod:`~cstep_bridge.sim.husky`).
Nothing here knows of rewards, ROS or training."""
