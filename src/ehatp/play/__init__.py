"""``ehatp play``: a person plays the human against the robot's policy, in a browser.

:mod:`.session` is the play itself (no web): what the participant perceives, its moves, live
replanning, the session log and its replay; :mod:`.views` what a page draws (per-domain view
hooks); :mod:`.server` the web server (Starlette, ``ehatp[play]``). See docs/play.md.
"""
