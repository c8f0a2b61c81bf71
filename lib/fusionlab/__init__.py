"""fusionlab"""
