"""The project's C++ programs as the tests run them: from the sourced
install space (CMAKE_PREFIX_PATH), not from a build tree."""
import os


def installed_tool(name):
    """The path of program `name` (lib/semantic_exploration/<name>) in the first prefix that holds it;
    fails the test, naming the prefixes searched, if none does."""
    tools = [os.path.join(p, "lib", "semantic_exploration", name)
             for p in os.environ.get("CMAKE_PREFIX_PATH", "").split(":") if p]
    tool = next((t for t in tools if os.access(t, os.X_OK)), None)
    assert tool, "%s is not built or the install space not sourced (searched %s)" % (name, tools)
    return tool
