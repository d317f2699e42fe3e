"""Physical models shared by sensors: sheet current flow, contact mechanics, force-sensing resistors."""
