"""Topside operator tools: the command composer (`commander`), iCommander in the terminal
(`icommander`) and liaison in the browser (`liaison`). Layer: above acomms and moos, below apps."""
