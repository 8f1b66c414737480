"""Student room: what runs in the student's kernel (the self-check, handing in)."""
