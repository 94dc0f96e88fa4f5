"""The drawings of the Logic screen: a program's or FB instance's body with live values."""
