from django.db import migrations, models


class Migration(migrations.Migration):
    dependencies = [
        ("exercises", "0002_exercise_pass_threshold_exercise_threshold_report"),
    ]

    operations = [
        migrations.AddField(
            model_name="exercise",
            name="key_poses_to_confirm",
            field=models.BooleanField(default=False),
        ),
    ]
