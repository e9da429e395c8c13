"""dacph-drake: Data-Assisted Control in the port-Hamiltonian framework on Drake."""
__version__ = "0.1.0"
