"""The one loop every door drives: fixed steps, events, commands, goals and expectations."""
