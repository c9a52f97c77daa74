//! SAC, TD3 and DDPG with recurrent sequence replay.
