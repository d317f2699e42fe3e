"""A blend passes its members' epochs on to its own epoch callback, each record labelled with the
member it comes from, so the run's TensorBoard holds every member's curves (the logger files a
record with `member: resmlp/fold0` under members/resmlp/fold0/)."""


def member_callback(callback, name: str):
    """`callback` as seen by member `name`: its records carry `member`, nested blends' labels
    joined outside-in (the weighted blend's resmlp, then its K-fold blend's fold0: resmlp/fold0)."""
    if callback is None:
        return None

    def labelled(record: dict) -> None:
        inner = record.get("member")
        callback({**record, "member": f"{name}/{inner}" if inner else name})
    return labelled
