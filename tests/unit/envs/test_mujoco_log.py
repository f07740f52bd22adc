import logging
import subprocess
import sys

SCRIPT = """
import logging
logging.basicConfig(level=logging.DEBUG, format="%(levelname)s %(name)s %(message)s")
from groupwise.envs import make_env
for _ in range(3):
    make_env("HalfCheetah").close()
"""


def test_mujoco_warnings_are_logged_once_not_printed():
    run = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True)
    lines = run.stderr.splitlines()
    assert not [line for line in lines if line.startswith("WARNING: compiler attribute")]
    infos = [line for line in lines if line.startswith("INFO groupwise.mujoco")]
    debugs = [line for line in lines if line.startswith("DEBUG groupwise.mujoco")]
    assert len(infos) == 1 and "settotalmass" in infos[0]
    assert len(debugs) == 2


def test_a_users_own_handler_stands():
    import mujoco

    from groupwise.envs.mujoco_log import log_mujoco_warnings

    def own(message: str) -> None:
        logging.getLogger("own").info(message)

    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(own)
    try:
        log_mujoco_warnings()
        assert mujoco.get_mju_user_warning() is own
    finally:
        mujoco.set_mju_user_warning(previous)
