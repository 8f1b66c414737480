"""The isolation layers of a grading child, one per module.

seccomp
    The kernel refuses process creation, exec, ptrace and raising limits.
limits
    Resource limits: address space, CPU time, file size, no core files.
audit
    A Python audit hook for clear error messages (not a security boundary).
"""
