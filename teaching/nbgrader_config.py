"""nbgrader's configuration for the lorisnb labs (run nbgrader from this folder; `make student`,
`make grade` do). Layout: source/<lab>/ (instructor versions, with solutions and hidden tests),
release/<lab>/ (student versions, generated), submitted/<student>/<lab>/, autograded/, feedback/."""

c = get_config()  # noqa: F821 (nbgrader provides it)
c.CourseDirectory.root = "."
c.CourseDirectory.course_id = "lorisnb-lifelong-slam"
c.CourseDirectory.db_url = "sqlite:///gradebook.db"
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"
c.Execute.timeout = 60  # seconds per cell (nbgrader autograde, if used; `make grade` has its own sandbox limits)
c.Execute.interrupt_on_timeout = True
c.ExportApp.plugin_class = "nbgrader.plugins.CsvExportPlugin"
