import skidnav

# One thesis world: the 25 x 25-cell arena with obstacles, 20 headings, thesis slip (seed 2).
env = skidnav.make_env("obstacles", slip="thesis", seed=2)
thesis = {"alpha": 0.5, "gamma": 0.95, "epsilon": 0.1}
for name, extra in [("dyna-full", {"planning_steps": 100}), ("q-learning", {})]:
    agent = skidnav.make_agent(name, env, seed=0, **thesis, **extra)
    log = skidnav.train(agent, env, episodes=500, max_steps=300)
    print(f"{name}: converged after episode {skidnav.convergence_episode(log, env)}")
