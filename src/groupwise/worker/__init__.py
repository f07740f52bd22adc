"""The app's training worker: a process of its own beside the web server (`process`,
started and watched by `supervisor`) that runs each session's rounds through the loop's
own round halves (`groupwise.run.round`) and talks to the server only through the
database and the data directory. `web_teacher.WebTeacher` lets a user's program publish
rounds to the page the same way.
"""
